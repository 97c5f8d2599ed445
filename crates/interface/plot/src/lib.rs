//! Renders pendkit's figures from plain data (slices of `f64`, names, units) to SVG or PNG:
//! Bode plots, noise budgets, mode charts, mode shapes, the speed–accuracy trade-off, and
//! line plots for sweeps.
//!
//! The crate knows nothing of pendkit's models: callers hand it numbers with names and
//! units. Each figure is a data struct with public fields and a `new` that fills sensible
//! defaults; every figure implements [`Figure`]:
//!
//! | figure | what it shows |
//! |---|---|
//! | [`BodePlot`] | magnitude (log-log) and phase (degrees, lin-log) of complex responses against frequency |
//! | [`NoiseBudget`] | an ASD total and its named contributions, log-log |
//! | [`ModeChart`] | mode frequencies as markers in rows by degree-of-freedom family; unstable modes at their growth rate |
//! | [`ModeShapePlot`] | side (x–z) and front (y–z) views of bodies and wires at rest and displaced along a mode |
//! | [`TradeoffChart`] | time against error of model variants, Pareto front marked ([`pareto_front`]) |
//! | [`LinePlot`] | any number of series against a swept parameter, linear or log axes |
//!
//! [`Figure::render`] writes a file in the format its extension names (`.svg` or `.png`,
//! anything else is [`PlotError::UnsupportedFormat`]); [`Figure::to_svg`] returns the SVG
//! as a string that can be put inline in a self-contained HTML page (no external
//! references, no scripts); [`Figure::to_png`] returns PNG bytes. Text is laid out with the
//! bundled DejaVu Sans font (its licence is in `fonts/`), so PNG output needs no font on the
//! machine, and SVG names that family first.
//!
//! # Data that cannot be drawn
//!
//! Nothing here panics on user data. The rules:
//! - Curves (Bode, noise budget, line plot): a point that is not finite, or not positive on
//!   a logarithmic axis (a zero magnitude, a NaN phase), is skipped and breaks the line; a
//!   stretch of one point is drawn as a dot. A curve with nothing to draw stays in the
//!   legend marked "(nothing to draw)". A figure with no series, or with no drawable point
//!   at all, is [`PlotError::NothingToPlot`]. Arrays that must pair up but differ in length
//!   are [`PlotError::LengthMismatch`].
//! - Ranges: an axis whose values are all equal is opened around them (±10 %, or ±1 around
//!   zero; half a decade each way on a log axis).
//! - Lists of discrete items (modes, trade-off variants, bodies) are checked strictly: a
//!   NaN or infinite value is [`PlotError::NotFinite`], an impossible one (a negative time,
//!   a body size below zero) [`PlotError::InvalidInput`], each naming the item.
//! - Figure sizes are checked ([`PlotError::InvalidSize`]).
//!
//! # Example
//!
//! ```
//! use pendkit_plot::{Axis, Figure, LinePlot, Scale, Series};
//!
//! let mut plot = LinePlot::new(
//!     "Pendulum frequency against length",
//!     Axis::new("wire length", "m", Scale::Linear),
//!     Axis::new("frequency", "Hz", Scale::Log),
//! );
//! let lengths: Vec<f64> = (1..=20).map(|i| 0.1 * f64::from(i)).collect();
//! let frequencies = lengths
//!     .iter()
//!     .map(|l| (9.81 / l).sqrt() / (2.0 * std::f64::consts::PI))
//!     .collect();
//! plot.series.push(Series::new("simple pendulum", lengths, frequencies));
//! let svg = plot.to_svg()?;
//! assert!(svg.starts_with("<svg") && svg.contains("wire length (m)"));
//! # Ok::<(), pendkit_plot::PlotError>(())
//! ```

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::{DrawingArea, DrawingBackend};

/// The plotters version this crate draws with, for [`Figure::draw`] on a backend of one's
/// own.
pub use plotters;

mod axis;
mod bode;
mod canvas;
mod chart;
mod error;
mod font;
mod labels;
mod lines;
mod mode_chart;
mod mode_shape;
mod noise;
mod output;
mod style;
mod tradeoff;

pub use axis::{Axis, Scale};
pub use bode::{BodePlot, BodeSeries, PhaseDisplay};
pub use error::PlotError;
pub use lines::{LinePlot, Series};
pub use mode_chart::{DEFAULT_FAMILY_ORDER, ModeChart, ModeMarker};
pub use mode_shape::{
    Amplitude, BodyAxis, BodyOutline, ModeShapePlot, Orientation, Solid, WireSegment,
};
pub use noise::{Contribution, NoiseBudget};
pub use output::{Format, MAX_AREA_PX, MAX_SIDE_PX, MIN_SIDE_PX};
pub use tradeoff::{TradeoffChart, TradeoffPoint, pareto_front};

/// A figure: a size and a way to draw itself. Output goes through the provided methods.
pub trait Figure {
    /// Width and height in pixels (SVG user units; PNG pixels).
    fn size(&self) -> (u32, u32);

    /// Checks the data and draws the figure on `area` (white background already filled).
    /// Fails with the first problem found in the data, before drawing anything.
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), PlotError>;

    /// The figure as an SVG document: starts with `<svg`, no XML prolog, no external
    /// references, so it can be embedded inline in HTML.
    fn to_svg(&self) -> Result<String, PlotError> {
        output::to_svg(self)
    }

    /// The figure as the contents of a PNG file (8-bit RGB).
    fn to_png(&self) -> Result<Vec<u8>, PlotError> {
        output::to_png(self)
    }

    /// Writes the figure to `path` as SVG or PNG, chosen by the extension (any case), whole
    /// or not at all (`pendkit_export::write_whole`), replacing an existing file. Nothing
    /// is written when the extension, the size or the data is wrong.
    fn render(&self, path: impl AsRef<Path>) -> Result<(), PlotError> {
        output::render(self, path.as_ref())
    }
}
