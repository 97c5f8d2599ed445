//! Shared look: colours, text sizes, line and marker styles, and the legend drawn beside a
//! chart.

use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::PlotError;
use crate::canvas::PLOTTERS_SIZE_PER_EM;
use crate::font::SVG_FAMILY;

/// Text sizes (em, pixels).
pub(crate) const TITLE_EM: f64 = 20.0;
pub(crate) const SUBTITLE_EM: f64 = 15.0;
pub(crate) const AXIS_TITLE_EM: f64 = 16.0;
pub(crate) const TICK_EM: f64 = 14.0;
pub(crate) const LEGEND_EM: f64 = 14.0;
pub(crate) const ANNOTATION_EM: f64 = 12.0;

/// Colours for series, in order (the widely used "tab10" set: distinguishable, and readable
/// for the commonest colour-vision deficiencies when combined with the dash patterns).
pub(crate) const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

pub(crate) const INK: RGBColor = RGBColor(0, 0, 0);
pub(crate) const GRID_MAJOR: RGBColor = RGBColor(205, 205, 205);
pub(crate) const GRID_MINOR: RGBColor = RGBColor(235, 235, 235);
pub(crate) const HIGHLIGHT: RGBColor = RGBColor(214, 39, 40);

/// A text style of `em` pixels in the figures' font.
pub(crate) fn text(em: f64) -> TextStyle<'static> {
    TextStyle::from((FontFamily::Name(SVG_FAMILY), em * PLOTTERS_SIZE_PER_EM)).color(&INK)
}

/// How a line is stroked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Dash {
    Solid,
    Dashed,
    Dotted,
}

/// Colour, width (pixels) and dash pattern of a line.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Stroke {
    pub(crate) color: RGBColor,
    pub(crate) width: u32,
    pub(crate) dash: Dash,
}

impl Stroke {
    pub(crate) fn solid(color: RGBColor, width: u32) -> Self {
        Stroke {
            color,
            width,
            dash: Dash::Solid,
        }
    }

    /// The i-th series style: the palette's colours, then the same colours dashed, then
    /// dotted, so that up to 30 series stay distinct.
    pub(crate) fn series(index: usize, width: u32) -> Self {
        let dash = match (index / PALETTE.len()) % 3 {
            0 => Dash::Solid,
            1 => Dash::Dashed,
            _ => Dash::Dotted,
        };
        Stroke {
            color: PALETTE[index % PALETTE.len()],
            width,
            dash,
        }
    }

    pub(crate) fn shape(&self) -> ShapeStyle {
        ShapeStyle {
            color: self.color.to_rgba(),
            filled: false,
            stroke_width: self.width,
        }
    }

    /// Dash and gap lengths in pixels.
    fn pattern(&self) -> Option<(i32, i32)> {
        let w = self.width as i32;
        match self.dash {
            Dash::Solid => None,
            Dash::Dashed => Some((6 + 2 * w, 3 + 2 * w)),
            Dash::Dotted => Some((w.max(1) + 1, 2 + 2 * w)),
        }
    }
}

/// Marker shapes for points.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Marker {
    Circle,
    Cross,
    Square,
}

/// Shape, colour, size (pixels from centre to edge) and fill of a point marker.
#[derive(Debug, Clone, Copy)]
pub(crate) struct MarkerStyle {
    pub(crate) marker: Marker,
    pub(crate) color: RGBColor,
    pub(crate) size: i32,
    pub(crate) filled: bool,
}

impl MarkerStyle {
    pub(crate) fn new(marker: Marker, color: RGBColor, size: i32, filled: bool) -> Self {
        MarkerStyle {
            marker,
            color,
            size,
            filled,
        }
    }
}

/// Draws a line through backend pixel points on `area`.
pub(crate) fn draw_pixel_line<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    points: &[(i32, i32)],
    stroke: &Stroke,
) -> Result<(), PlotError> {
    match stroke.pattern() {
        None => area.draw(&PathElement::new(points.to_vec(), stroke.shape()))?,
        Some((dash, gap)) => area.draw(&DashedPathElement::new(
            points.to_vec(),
            dash,
            gap,
            stroke.shape(),
        ))?,
    }
    Ok(())
}

/// Draws a marker centred on a backend pixel point of `area`.
pub(crate) fn draw_pixel_marker<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    (x, y): (i32, i32),
    style: &MarkerStyle,
) -> Result<(), PlotError> {
    let s = style.size.max(1);
    let shape = ShapeStyle {
        color: style.color.to_rgba(),
        filled: style.filled,
        stroke_width: 2,
    };
    match style.marker {
        Marker::Circle => area.draw(&Circle::new((x, y), s, shape))?,
        Marker::Square => area.draw(&Rectangle::new([(x - s, y - s), (x + s, y + s)], shape))?,
        Marker::Cross => {
            let stroke = shape.stroke_width(3);
            area.draw(&PathElement::new(
                vec![(x - s, y - s), (x + s, y + s)],
                stroke,
            ))?;
            area.draw(&PathElement::new(
                vec![(x - s, y + s), (x + s, y - s)],
                stroke,
            ))?;
        }
    }
    Ok(())
}

/// A pixel drawing area.
pub(crate) type Area<DB> = DrawingArea<DB, Shift>;

/// One line of a legend: a sample of the line and/or marker, then the text.
#[derive(Debug, Clone)]
pub(crate) struct LegendEntry {
    pub(crate) label: String,
    pub(crate) stroke: Option<Stroke>,
    pub(crate) marker: Option<MarkerStyle>,
}

/// Width of the line sample and the gaps around it, pixels.
const SAMPLE_WIDTH: i32 = 30;
const LEGEND_PAD: i32 = 10;

/// Splits `area` into the chart area (left) and a legend column (right) wide enough for the
/// longest entry, at most `max_fraction` of the width. No legend column for no entries.
pub(crate) fn split_for_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
    max_fraction: f64,
) -> Result<(Area<DB>, Option<Area<DB>>), PlotError> {
    if entries.is_empty() {
        return Ok((area.clone(), None));
    }
    let style = text(LEGEND_EM);
    let mut widest = 0u32;
    for entry in entries {
        widest = widest.max(area.estimate_text_size(&entry.label, &style)?.0);
    }
    let (width, _) = area.dim_in_pixel();
    let wanted = widest as i32 + SAMPLE_WIDTH + 4 * LEGEND_PAD;
    let limit = (f64::from(width) * max_fraction) as i32;
    let legend_width = wanted.min(limit).max(0);
    let (chart, legend) = area.split_horizontally(width as i32 - legend_width);
    Ok((chart, Some(legend)))
}

/// Draws the entries top-down in `area`, starting `top` pixels down. A label wider than the
/// column wraps onto a second line (and is cut with an ellipsis if still too wide); a list
/// too long for the column is drawn in smaller type.
pub(crate) fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
    top: i32,
) -> Result<(), PlotError> {
    if entries.is_empty() {
        return Ok(());
    }
    let (width, height) = area.dim_in_pixel();
    let available = f64::from((height as i32 - top - LEGEND_PAD).max(1));
    let text_x = LEGEND_PAD + SAMPLE_WIDTH + LEGEND_PAD / 2;
    let text_room = width as i32 - text_x - LEGEND_PAD / 2;
    // Line height 1.25 em, and 0.45 em between entries.
    let layout = |em: f64| -> Result<(Vec<Vec<String>>, f64), PlotError> {
        let style = text(em);
        let wrapped = entries
            .iter()
            .map(|e| wrap_text(area, &e.label, &style, text_room))
            .collect::<Result<Vec<_>, _>>()?;
        let lines: usize = wrapped.iter().map(Vec::len).sum();
        Ok((
            wrapped,
            em * (1.25 * lines as f64 + 0.45 * entries.len() as f64),
        ))
    };
    let (mut wrapped, needed) = layout(LEGEND_EM)?;
    let mut em = LEGEND_EM;
    if needed > available {
        em = (LEGEND_EM * available / needed).max(6.0);
        wrapped = layout(em)?.0;
    }
    let style = text(em).pos(Pos::new(HPos::Left, VPos::Center));
    let line = 1.25 * em;
    let mut y = f64::from(top) + 0.5 * line;
    for (entry, lines) in entries.iter().zip(&wrapped) {
        let sample_y = y.round() as i32;
        if let Some(stroke) = &entry.stroke {
            draw_pixel_line(
                area,
                &[
                    (LEGEND_PAD, sample_y),
                    (LEGEND_PAD + SAMPLE_WIDTH, sample_y),
                ],
                stroke,
            )?;
        }
        if let Some(marker) = &entry.marker {
            draw_pixel_marker(area, (LEGEND_PAD + SAMPLE_WIDTH / 2, sample_y), marker)?;
        }
        for text_line in lines {
            area.draw_text(text_line, &style, (text_x, y.round() as i32))?;
            y += line;
        }
        y += 0.45 * em;
    }
    Ok(())
}

/// `label` broken at spaces into at most two lines of at most `room` pixels; a second line
/// that is still too wide is cut with an ellipsis.
fn wrap_text<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    label: &str,
    style: &TextStyle,
    room: i32,
) -> Result<Vec<String>, PlotError> {
    let fits = |t: &str| -> Result<bool, PlotError> {
        Ok(area.estimate_text_size(t, style)?.0 as i32 <= room)
    };
    if fits(label)? {
        return Ok(vec![label.to_string()]);
    }
    // The longest first line that fits, broken at a space.
    let words: Vec<&str> = label.split(' ').collect();
    let mut split = 0;
    for n in 1..words.len() {
        if fits(&words[..n].join(" "))? {
            split = n;
        } else {
            break;
        }
    }
    if split == 0 {
        return Ok(vec![fit_text(area, label, style, room)?]);
    }
    let first = words[..split].join(" ");
    let rest = words[split..].join(" ");
    Ok(vec![first, fit_text(area, &rest, style, room)?])
}

/// `label`, cut and ended with an ellipsis if it is wider than `room` pixels.
pub(crate) fn fit_text<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    label: &str,
    style: &TextStyle,
    room: i32,
) -> Result<String, PlotError> {
    if area.estimate_text_size(label, style)?.0 as i32 <= room {
        return Ok(label.to_string());
    }
    let mut chars: Vec<char> = label.chars().collect();
    while !chars.is_empty() {
        chars.pop();
        let candidate: String = chars.iter().chain(std::iter::once(&'…')).collect();
        if area.estimate_text_size(&candidate, style)?.0 as i32 <= room {
            return Ok(candidate);
        }
    }
    Ok(String::new())
}

/// Draws the figure title (and an optional second line) at the top of `area` and returns
/// the area below them.
pub(crate) fn draw_title<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    subtitle: Option<&str>,
) -> Result<DrawingArea<DB, Shift>, PlotError> {
    let mut rest = area.clone();
    if !title.is_empty() {
        rest = rest.titled(title, text(TITLE_EM))?;
    }
    if let Some(subtitle) = subtitle.filter(|s| !s.is_empty()) {
        rest = rest.titled(subtitle, text(SUBTITLE_EM))?;
    }
    Ok(rest)
}
