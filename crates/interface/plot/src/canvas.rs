//! The two drawing backends figures are rendered on.
//!
//! - [`SvgCanvas`]: plotters' SVG backend, with text measured by the bundled font (plotters
//!   alone guesses 0.7 em per byte), so the layout is the one the PNG gets.
//! - [`PngCanvas`]: a pixel canvas of our own. Shapes go through plotters' CPU rasteriser on
//!   a buffer [`SUPERSAMPLING`] times larger in each direction, averaged down at the end (so
//!   lines and fills are antialiased); text is rasterised by ab_glyph from the bundled font.
//!   No system font and no bitmap backend is needed, which keeps plotters' text features
//!   off: enabling plotters' own `ab_glyph` feature would also switch it on for every other
//!   user of plotters in a build (criterion's reports), where no font is registered.

use plotters::backend::SVGBackend;
use plotters_backend::text_anchor::{HPos, VPos};
use plotters_backend::{
    BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingBackend, DrawingErrorKind,
    FontTransform,
};

use crate::font;

/// plotters' text sizes are 1.24 times the em size (its SVG backend writes
/// `font-size = size / 1.24`); both canvases keep that convention.
pub(crate) const PLOTTERS_SIZE_PER_EM: f64 = 1.24;

/// Samples per output pixel along each axis of the PNG canvas.
pub(crate) const SUPERSAMPLING: u32 = 3;

fn font_error<E: std::error::Error + Send + Sync>(
    error: font::FontUnavailable,
) -> DrawingErrorKind<E> {
    DrawingErrorKind::FontError(Box::new(error))
}

/// Width and height of `text` in pixels with the bundled font, as plotters' layout wants it.
fn measure_text<S: BackendTextStyle, E: std::error::Error + Send + Sync>(
    text: &str,
    style: &S,
) -> Result<(u32, u32), DrawingErrorKind<E>> {
    let font = font::bundled().map_err(font_error)?;
    let (width, height) = font.measure(text, style.size() / PLOTTERS_SIZE_PER_EM);
    Ok((width.ceil().max(0.0) as u32, height.ceil().max(0.0) as u32))
}

/// plotters' SVG backend with text measured by the bundled font.
pub(crate) struct SvgCanvas<'a> {
    inner: SVGBackend<'a>,
}

impl<'a> SvgCanvas<'a> {
    /// An SVG document of `size` pixels written into `buffer`.
    pub(crate) fn new(buffer: &'a mut String, size: (u32, u32)) -> Self {
        SvgCanvas {
            inner: SVGBackend::with_string(buffer, size),
        }
    }
}

type SvgError = <SVGBackend<'static> as DrawingBackend>::ErrorType;

impl DrawingBackend for SvgCanvas<'_> {
    type ErrorType = SvgError;

    fn get_size(&self) -> (u32, u32) {
        self.inner.get_size()
    }

    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<SvgError>> {
        self.inner.ensure_prepared()
    }

    fn present(&mut self) -> Result<(), DrawingErrorKind<SvgError>> {
        self.inner.present()
    }

    fn draw_pixel(
        &mut self,
        point: BackendCoord,
        color: BackendColor,
    ) -> Result<(), DrawingErrorKind<SvgError>> {
        self.inner.draw_pixel(point, color)
    }

    fn draw_line<S: BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> Result<(), DrawingErrorKind<SvgError>> {
        self.inner.draw_line(from, to, style)
    }

    fn draw_rect<S: BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<SvgError>> {
        self.inner.draw_rect(upper_left, bottom_right, style, fill)
    }

    fn draw_path<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<SvgError>> {
        self.inner.draw_path(path, style)
    }

    fn draw_circle<S: BackendStyle>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<SvgError>> {
        self.inner.draw_circle(center, radius, style, fill)
    }

    fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<SvgError>> {
        self.inner.fill_polygon(vert, style)
    }

    fn draw_text<T: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &T,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<SvgError>> {
        self.inner.draw_text(text, style, pos)
    }

    fn estimate_text_size<T: BackendTextStyle>(
        &self,
        text: &str,
        style: &T,
    ) -> Result<(u32, u32), DrawingErrorKind<SvgError>> {
        measure_text(text, style)
    }
}

/// The PNG canvas never fails by itself: its only error is the font's, reported as a font
/// error.
type NoError = std::convert::Infallible;

/// An RGB pixel buffer that blends every pixel it is given; plotters' rasteriser draws the
/// shapes on it through [`DrawingBackend::draw_pixel`].
struct SampleBuffer {
    width: u32,
    height: u32,
    rgb: Vec<u8>,
}

impl DrawingBackend for SampleBuffer {
    type ErrorType = NoError;

    fn get_size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<NoError>> {
        Ok(())
    }

    fn present(&mut self) -> Result<(), DrawingErrorKind<NoError>> {
        Ok(())
    }

    fn draw_pixel(
        &mut self,
        (x, y): BackendCoord,
        color: BackendColor,
    ) -> Result<(), DrawingErrorKind<NoError>> {
        if x < 0 || y < 0 || x >= self.width as i32 || y >= self.height as i32 {
            return Ok(());
        }
        let alpha = color.alpha.clamp(0.0, 1.0);
        if alpha == 0.0 {
            return Ok(());
        }
        let start = (y as usize * self.width as usize + x as usize) * 3;
        if let Some(pixel) = self.rgb.get_mut(start..start + 3) {
            let source = [color.rgb.0, color.rgb.1, color.rgb.2];
            for (channel, value) in pixel.iter_mut().zip(source) {
                let blended =
                    f64::from(*channel) + (f64::from(value) - f64::from(*channel)) * alpha;
                *channel = blended.round().clamp(0.0, 255.0) as u8;
            }
        }
        Ok(())
    }
}

/// A style whose stroke is `factor` times wider: line widths scale with the supersampling.
struct WiderStroke<'a, S> {
    style: &'a S,
    factor: u32,
}

impl<S: BackendStyle> BackendStyle for WiderStroke<'_, S> {
    fn color(&self) -> BackendColor {
        self.style.color()
    }

    fn stroke_width(&self) -> u32 {
        self.style.stroke_width().saturating_mul(self.factor)
    }
}

/// The supersampled pixels of a PNG figure, white to start with: drawn on through a
/// [`PngCanvas`], then averaged down by [`PngPixels::to_rgb`].
pub(crate) struct PngPixels {
    width: u32,
    height: u32,
    samples: SampleBuffer,
}

impl PngPixels {
    /// White pixels for a figure of `size` output pixels.
    pub(crate) fn new((width, height): (u32, u32)) -> Self {
        let (sample_width, sample_height) = (width * SUPERSAMPLING, height * SUPERSAMPLING);
        PngPixels {
            width,
            height,
            samples: SampleBuffer {
                width: sample_width,
                height: sample_height,
                rgb: vec![255; sample_width as usize * sample_height as usize * 3],
            },
        }
    }

    /// The output image, row-major 8-bit RGB, each pixel the mean of its samples.
    pub(crate) fn to_rgb(&self) -> Vec<u8> {
        let factor = SUPERSAMPLING as usize;
        let (width, height) = (self.width as usize, self.height as usize);
        let sample_width = self.samples.width as usize;
        let mut rgb = vec![0u8; width * height * 3];
        let count = (factor * factor) as u32;
        for (index, out) in rgb.chunks_exact_mut(3).enumerate() {
            let (x, y) = (index % width, index / width);
            let mut sum = [0u32; 3];
            for sy in y * factor..(y + 1) * factor {
                let row = sy * sample_width;
                for sx in x * factor..(x + 1) * factor {
                    let start = (row + sx) * 3;
                    if let Some(sample) = self.samples.rgb.get(start..start + 3) {
                        for (total, value) in sum.iter_mut().zip(sample) {
                            *total += u32::from(*value);
                        }
                    }
                }
            }
            for (channel, total) in out.iter_mut().zip(sum) {
                *channel = ((total + count / 2) / count) as u8;
            }
        }
        rgb
    }

    /// Size in output pixels.
    pub(crate) fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }
}

/// The drawing backend that draws on [`PngPixels`].
pub(crate) struct PngCanvas<'a> {
    width: u32,
    height: u32,
    samples: &'a mut SampleBuffer,
}

impl<'a> PngCanvas<'a> {
    /// A canvas drawing on `pixels`.
    pub(crate) fn new(pixels: &'a mut PngPixels) -> Self {
        PngCanvas {
            width: pixels.width,
            height: pixels.height,
            samples: &mut pixels.samples,
        }
    }

    /// Coordinates far outside the canvas are pulled in to this margin (in output pixels)
    /// before scaling: the rasteriser's work grows with a shape's extent, and the figures
    /// never draw that far out.
    fn clamp_margin(&self) -> i32 {
        4 * self.width.max(self.height) as i32
    }

    /// The sample at the centre of an output pixel.
    fn sample_centre(&self, (x, y): BackendCoord) -> BackendCoord {
        let margin = self.clamp_margin();
        let factor = SUPERSAMPLING as i32;
        (
            x.clamp(-margin, margin) * factor + factor / 2,
            y.clamp(-margin, margin) * factor + factor / 2,
        )
    }

    /// The top-left sample of an output pixel.
    fn sample_corner(&self, (x, y): BackendCoord) -> BackendCoord {
        let margin = self.clamp_margin();
        let factor = SUPERSAMPLING as i32;
        (
            x.clamp(-margin, margin) * factor,
            y.clamp(-margin, margin) * factor,
        )
    }

    fn wider<'s, S: BackendStyle>(style: &'s S) -> WiderStroke<'s, S> {
        WiderStroke {
            style,
            factor: SUPERSAMPLING,
        }
    }
}

impl DrawingBackend for PngCanvas<'_> {
    type ErrorType = NoError;

    fn get_size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<NoError>> {
        Ok(())
    }

    fn present(&mut self) -> Result<(), DrawingErrorKind<NoError>> {
        Ok(())
    }

    fn draw_pixel(
        &mut self,
        point: BackendCoord,
        color: BackendColor,
    ) -> Result<(), DrawingErrorKind<NoError>> {
        let (x0, y0) = self.sample_corner(point);
        let factor = SUPERSAMPLING as i32;
        for y in y0..y0 + factor {
            for x in x0..x0 + factor {
                self.samples.draw_pixel((x, y), color)?;
            }
        }
        Ok(())
    }

    fn draw_line<S: BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> Result<(), DrawingErrorKind<NoError>> {
        let (from, to) = (self.sample_centre(from), self.sample_centre(to));
        self.samples.draw_line(from, to, &Self::wider(style))
    }

    fn draw_rect<S: BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<NoError>> {
        if fill {
            // A filled rectangle covers whole output pixels, corners included.
            let factor = SUPERSAMPLING as i32;
            let (x0, y0) = self.sample_corner(upper_left);
            let (x1, y1) = self.sample_corner(bottom_right);
            let color = style.color();
            self.samples
                .draw_rect((x0, y0), (x1 + factor - 1, y1 + factor - 1), &color, true)
        } else {
            let (upper_left, bottom_right) = (
                self.sample_centre(upper_left),
                self.sample_centre(bottom_right),
            );
            self.samples
                .draw_rect(upper_left, bottom_right, &Self::wider(style), false)
        }
    }

    fn draw_path<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<NoError>> {
        // Segment by segment, with a disc at each joint: plotters' outline of a whole wide
        // path is filled even-odd and leaves holes where a sharp peak folds it over itself.
        let points: Vec<BackendCoord> = path.into_iter().map(|p| self.sample_centre(p)).collect();
        let wide = Self::wider(style);
        let color = style.color();
        let joint_radius = wide.stroke_width() / 2;
        for (index, pair) in points.windows(2).enumerate() {
            if let [from, to] = pair {
                self.samples.draw_line(*from, *to, &wide)?;
                if index > 0 && joint_radius > 1 {
                    self.samples
                        .draw_circle(*from, joint_radius, &color, true)?;
                }
            }
        }
        Ok(())
    }

    fn draw_circle<S: BackendStyle>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<NoError>> {
        let center = self.sample_centre(center);
        let radius = radius.saturating_mul(SUPERSAMPLING);
        self.samples
            .draw_circle(center, radius, &Self::wider(style), fill)
    }

    fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<NoError>> {
        let vertices: Vec<BackendCoord> = vert.into_iter().map(|p| self.sample_centre(p)).collect();
        self.samples.fill_polygon(vertices, &style.color())
    }

    fn draw_text<T: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &T,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<NoError>> {
        let color = style.color();
        if color.alpha == 0.0 || text.is_empty() {
            return Ok(());
        }
        let font = font::bundled().map_err(font_error)?;
        let em = style.size() / PLOTTERS_SIZE_PER_EM * f64::from(SUPERSAMPLING);
        let (width, _) = font.measure(text, em);
        // The same anchoring as plotters' SVG backend writes (text-anchor, and dy of
        // 0.76 em, 0.5 ex or -0.5 ex), so both formats put text in the same place.
        let anchor = style.anchor();
        let dx = match anchor.h_pos {
            HPos::Left => 0.0,
            HPos::Center => -width / 2.0,
            HPos::Right => -width,
        };
        let dy = match anchor.v_pos {
            VPos::Top => 0.76 * em,
            VPos::Center => 0.5 * font.x_height(em),
            VPos::Bottom => -0.5 * font.x_height(em),
        };
        let (dx, dy) = (dx.round() as i32, dy.round() as i32);
        let transform = style.transform();
        let origin = self.sample_centre(pos);
        let samples = &mut *self.samples;
        font.rasterize(text, em, |x, y, coverage| {
            let (rx, ry) = match transform {
                FontTransform::None => (x + dx, y + dy),
                _ => transform.transform(x + dx, y + dy),
            };
            // Blending into the buffer cannot fail (its error type is uninhabited).
            let _ = samples.draw_pixel(
                (origin.0 + rx, origin.1 + ry),
                color.mix(f64::from(coverage)),
            );
        });
        Ok(())
    }

    fn estimate_text_size<T: BackendTextStyle>(
        &self,
        text: &str,
        style: &T,
    ) -> Result<(u32, u32), DrawingErrorKind<NoError>> {
        measure_text(text, style)
    }
}
