//! The one error type of the crate.

use std::path::PathBuf;

use plotters::drawing::DrawingAreaErrorKind;

/// Everything that can go wrong while checking, drawing or writing a figure. Each variant
/// names the figure and the piece of input (or file) at fault.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The file name does not end in `.svg` or `.png`.
    #[error(
        "cannot tell the figure format of `{path}`: the file name must end in .svg or .png",
        path = path.display()
    )]
    UnsupportedFormat {
        /// The file name given.
        path: PathBuf,
    },
    /// The figure has nothing that can be drawn: no series, or no point that is finite (and
    /// positive on a logarithmic axis).
    #[error("{figure}: nothing to plot: {reason}")]
    NothingToPlot {
        /// Which figure.
        figure: &'static str,
        /// What is missing.
        reason: String,
    },
    /// Two arrays that must pair up have different lengths.
    #[error("{figure}: {what} has {found} values but {expected} were expected")]
    LengthMismatch {
        /// Which figure.
        figure: &'static str,
        /// Which array, e.g. "response of series `x3/x00`".
        what: String,
        /// The length it must have.
        expected: usize,
        /// The length it has.
        found: usize,
    },
    /// A value that must be finite is NaN or infinite.
    #[error("{figure}: {what} is {value}, not a finite number")]
    NotFinite {
        /// Which figure.
        figure: &'static str,
        /// Which value, e.g. "seconds of variant `stage 1a`".
        what: String,
        /// The value found.
        value: f64,
    },
    /// A value is finite but outside what the figure accepts (a negative size, a zero time on
    /// a logarithmic axis, a matrix that is not a rotation, ...).
    #[error("{figure}: {what}: {reason}")]
    InvalidInput {
        /// Which figure.
        figure: &'static str,
        /// Which value.
        what: String,
        /// What is wrong with it.
        reason: String,
    },
    /// The requested figure size is outside the supported range.
    #[error(
        "figure size {width}x{height} px is not supported: each side must be {min}..={max} px \
         and the area at most {area} px",
        min = crate::output::MIN_SIDE_PX,
        max = crate::output::MAX_SIDE_PX,
        area = crate::output::MAX_AREA_PX
    )]
    InvalidSize {
        /// Requested width (px).
        width: u32,
        /// Requested height (px).
        height: u32,
    },
    /// The drawing library reported a failure (not expected with the crate's own backends).
    #[error("drawing failed: {0}")]
    Drawing(String),
    /// PNG encoding failed.
    #[error("encoding PNG: {0}")]
    PngEncoding(String),
    /// Writing the output file failed.
    #[error("writing `{path}`: {source}", path = path.display())]
    Io {
        /// The file being written.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
}

impl<E: std::error::Error + Send + Sync> From<DrawingAreaErrorKind<E>> for PlotError {
    fn from(error: DrawingAreaErrorKind<E>) -> Self {
        PlotError::Drawing(error.to_string())
    }
}
