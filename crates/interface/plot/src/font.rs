//! The bundled font (DejaVu Sans, `fonts/`): text measurement for the layout of every
//! figure, and glyph rasterisation for PNG output, with no font installed on the machine.
//!
//! Sizes are in em pixels (the CSS `font-size`), positions relative to the left end of the
//! text's baseline, y down.

use std::sync::OnceLock;

use ab_glyph::{Font, FontRef, GlyphId, PxScale, ScaleFont, point};

static FONT_BYTES: &[u8] = include_bytes!("../fonts/DejaVuSans.ttf");

/// Family names written into SVG files: the bundled face first, so a viewer that has it
/// draws text with the metrics the layout was made with, then close fallbacks.
pub(crate) const SVG_FAMILY: &str = "DejaVu Sans, Verdana, sans-serif";

/// The bundled font could not be read (a corrupted build; never expected).
#[derive(Debug, Clone, Copy)]
pub(crate) struct FontUnavailable;

impl std::fmt::Display for FontUnavailable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("the bundled font (DejaVu Sans) could not be read")
    }
}

impl std::error::Error for FontUnavailable {}

/// The parsed font and the unscaled metrics the layout needs.
pub(crate) struct BundledFont {
    font: FontRef<'static>,
    /// Font units per em.
    units_per_em: f32,
    /// Ascent minus descent, font units (what ab_glyph's `PxScale` is a pixel size of).
    height_units: f32,
    /// Height of a lower-case x, font units (the CSS `ex`).
    x_height_units: f32,
}

/// The bundled font, parsed once.
pub(crate) fn bundled() -> Result<&'static BundledFont, FontUnavailable> {
    static FONT: OnceLock<Option<BundledFont>> = OnceLock::new();
    FONT.get_or_init(|| {
        let font = FontRef::try_from_slice(FONT_BYTES).ok()?;
        let units_per_em = font.units_per_em()?;
        let x_height_units = font
            .outline(font.glyph_id('x'))
            // ab_glyph's outline bounds run y down: take the size, not the signed difference.
            .map_or(0.5 * units_per_em, |outline| {
                (outline.bounds.max.y - outline.bounds.min.y).abs()
            });
        Some(BundledFont {
            units_per_em,
            height_units: font.height_unscaled(),
            x_height_units,
            font,
        })
    })
    .as_ref()
    .ok_or(FontUnavailable)
}

impl BundledFont {
    /// ab_glyph's scale for an em size in pixels.
    fn scale(&self, em_px: f64) -> PxScale {
        PxScale::from((em_px as f32) * self.height_units / self.units_per_em)
    }

    /// Glyphs of `text` with their pen positions along the baseline (pixels), kerned; and the
    /// advance width of the whole text.
    fn layout(&self, text: &str, em_px: f64) -> (Vec<(GlyphId, f32)>, f32) {
        let scaled = self.font.as_scaled(self.scale(em_px));
        let mut pen = 0.0f32;
        let mut previous: Option<GlyphId> = None;
        let mut glyphs = Vec::with_capacity(text.len());
        for c in text.chars() {
            // Control characters (tabs, newlines) have no glyph: lay them out as spaces.
            let c = if c.is_control() { ' ' } else { c };
            let id = scaled.glyph_id(c);
            if let Some(previous) = previous {
                pen += scaled.kern(previous, id);
            }
            glyphs.push((id, pen));
            pen += scaled.h_advance(id);
            previous = Some(id);
        }
        (glyphs, pen)
    }

    /// Advance width of `text` and the font's line height (ascent minus descent), pixels.
    pub(crate) fn measure(&self, text: &str, em_px: f64) -> (f64, f64) {
        let (_, width) = self.layout(text, em_px);
        (f64::from(width), self.line_height(em_px))
    }

    /// Ascent minus descent at this size, pixels.
    pub(crate) fn line_height(&self, em_px: f64) -> f64 {
        em_px * f64::from(self.height_units / self.units_per_em)
    }

    /// Height of a lower-case x at this size (the CSS `ex`), pixels.
    pub(crate) fn x_height(&self, em_px: f64) -> f64 {
        em_px * f64::from(self.x_height_units / self.units_per_em)
    }

    /// Rasterises `text` with its baseline starting at the origin: calls `plot(x, y, coverage)`
    /// for every pixel the glyphs touch, coverage in 0..=1.
    pub(crate) fn rasterize(&self, text: &str, em_px: f64, mut plot: impl FnMut(i32, i32, f32)) {
        let scale = self.scale(em_px);
        let (glyphs, _) = self.layout(text, em_px);
        for (id, pen) in glyphs {
            let glyph = id.with_scale_and_position(scale, point(pen, 0.0));
            if let Some(outlined) = self.font.outline_glyph(glyph) {
                let bounds = outlined.px_bounds();
                let (left, top) = (bounds.min.x as i32, bounds.min.y as i32);
                outlined.draw(|x, y, coverage| {
                    plot(left + x as i32, top + y as i32, coverage);
                });
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bundled_font_parses_and_has_the_glyphs_figures_use() {
        let font = bundled().expect("bundled font");
        // Unit and label characters used by the figures: a missing glyph maps to id 0.
        for c in ['√', '°', '×', '–', '⁻', '³', '|', 'µ'] {
            assert_ne!(font.font.glyph_id(c).0, 0, "glyph for {c:?}");
        }
    }

    #[test]
    fn measurement_scales_with_size_and_length() {
        let font = bundled().expect("bundled font");
        let (w10, h10) = font.measure("frequency (Hz)", 10.0);
        let (w20, h20) = font.measure("frequency (Hz)", 20.0);
        // Widths and heights are linear in the size (same glyphs, same kerning).
        assert!((w20 / w10 - 2.0).abs() < 1e-6, "{w10} {w20}");
        assert!((h20 / h10 - 2.0).abs() < 1e-9);
        // DejaVu Sans: ascent 1901, descent -483, 2048 units per em (its hhea table).
        assert!(
            (h10 - 10.0 * (1901.0 + 483.0) / 2048.0).abs() < 1e-4,
            "{h10}"
        );
        // DejaVu Sans's x-height is 1120 units (its OS/2 table; the outline of 'x' spans it).
        assert!(
            (font.x_height(10.0) - 10.0 * 1120.0 / 2048.0).abs() < 0.05,
            "{}",
            font.x_height(10.0)
        );
        let (w_short, _) = font.measure("f", 10.0);
        assert!(w_short > 0.0 && w_short < w10);
        assert_eq!(font.measure("", 10.0).0, 0.0);
    }

    #[test]
    fn rasterised_text_covers_pixels_above_the_baseline() {
        let font = bundled().expect("bundled font");
        let mut pixels = Vec::new();
        font.rasterize("Hx", 20.0, |x, y, c| {
            if c > 0.5 {
                pixels.push((x, y));
            }
        });
        assert!(!pixels.is_empty());
        // Capital H sits on the baseline and reaches about 0.73 em up (cap height 1493/2048).
        let top = pixels.iter().map(|p| p.1).min().unwrap_or(0);
        let bottom = pixels.iter().map(|p| p.1).max().unwrap_or(0);
        assert!((-16..=-13).contains(&top), "top {top}");
        assert!((-1..=0).contains(&bottom), "bottom {bottom}");
    }
}
