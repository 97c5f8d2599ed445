//! Output: the format chosen from a file name, SVG text, PNG bytes, files.

use std::path::Path;

use plotters::prelude::*;

use crate::canvas::{PngCanvas, PngPixels, SvgCanvas};
use crate::{Figure, PlotError};

/// Smallest and largest figure side (pixels), and the largest area (pixels, a 4K frame):
/// PNG rendering holds 27 bytes per pixel while drawing.
pub const MIN_SIDE_PX: u32 = 64;
/// See [`MIN_SIDE_PX`].
pub const MAX_SIDE_PX: u32 = 8192;
/// See [`MIN_SIDE_PX`].
pub const MAX_AREA_PX: u64 = 3840 * 2160;

/// Output file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Scalable vector graphics (`.svg`): text stays text, no external references.
    Svg,
    /// Portable network graphics (`.png`): 8-bit RGB, one pixel per figure pixel.
    Png,
}

impl Format {
    /// The format named by the file extension (`.svg` or `.png`, any case).
    pub fn from_path(path: &Path) -> Result<Format, PlotError> {
        let extension = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match extension.as_deref() {
            Some("svg") => Ok(Format::Svg),
            Some("png") => Ok(Format::Png),
            _ => Err(PlotError::UnsupportedFormat {
                path: path.to_path_buf(),
            }),
        }
    }
}

/// Checks a figure size against the supported range.
pub(crate) fn checked_size((width, height): (u32, u32)) -> Result<(u32, u32), PlotError> {
    let sides_ok = (MIN_SIDE_PX..=MAX_SIDE_PX).contains(&width)
        && (MIN_SIDE_PX..=MAX_SIDE_PX).contains(&height);
    if sides_ok && u64::from(width) * u64::from(height) <= MAX_AREA_PX {
        Ok((width, height))
    } else {
        Err(PlotError::InvalidSize { width, height })
    }
}

/// The figure as an SVG document (starts with `<svg`, no XML prolog, so it can be put
/// inline in an HTML page as it is).
pub(crate) fn to_svg<F: Figure + ?Sized>(figure: &F) -> Result<String, PlotError> {
    let size = checked_size(figure.size())?;
    let mut svg = String::new();
    {
        let root = SvgCanvas::new(&mut svg, size).into_drawing_area();
        root.fill(&WHITE)?;
        figure.draw(&root)?;
        root.present()?;
    }
    Ok(svg)
}

/// The figure as PNG file contents.
pub(crate) fn to_png<F: Figure + ?Sized>(figure: &F) -> Result<Vec<u8>, PlotError> {
    let size = checked_size(figure.size())?;
    let mut pixels = PngPixels::new(size);
    {
        let root = PngCanvas::new(&mut pixels).into_drawing_area();
        root.fill(&WHITE)?;
        figure.draw(&root)?;
        root.present()?;
    }
    encode_png(&pixels.to_rgb(), pixels.size())
}

/// PNG file contents of an 8-bit RGB image.
fn encode_png(rgb: &[u8], (width, height): (u32, u32)) -> Result<Vec<u8>, PlotError> {
    let encoding = |e: png::EncodingError| PlotError::PngEncoding(e.to_string());
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(encoding)?;
        writer.write_image_data(rgb).map_err(encoding)?;
        writer.finish().map_err(encoding)?;
    }
    Ok(bytes)
}

/// Draws the figure and writes it to `path`, in the format its extension names, whole or
/// not at all (a temporary file renamed into place, replacing an existing file). Nothing
/// is written if the name or the figure is invalid.
pub(crate) fn render<F: Figure + ?Sized>(figure: &F, path: &Path) -> Result<(), PlotError> {
    let bytes = match Format::from_path(path)? {
        Format::Svg => to_svg(figure)?.into_bytes(),
        Format::Png => to_png(figure)?,
    };
    pendkit_export::write_bytes_whole(path, &bytes).map_err(|e| match e {
        pendkit_export::FileError::Io { path, source } => PlotError::Io { path, source },
        // write_bytes_whole replaces: it never refuses an existing file
        pendkit_export::FileError::Exists { path } => PlotError::Io {
            path,
            source: std::io::ErrorKind::AlreadyExists.into(),
        },
    })
}
