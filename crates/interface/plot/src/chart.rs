//! One chart panel: axes with a grid, tick labels and titles, and the curves and markers
//! drawn on it. Every figure is made of these panels.

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::PlotError;
use crate::axis::{AxisCoord, Scale, drawable};
use crate::labels::Rect;
use crate::style::{
    self, AXIS_TITLE_EM, GRID_MAJOR, GRID_MINOR, INK, MarkerStyle, Stroke, TICK_EM,
    draw_pixel_line, draw_pixel_marker,
};

/// Most major ticks per axis.
pub(crate) const MAX_MAJOR_TICKS: usize = 10;
/// Tick mark length (pixels); labels sit twice as far from the axis.
const TICK_MARK: i32 = 5;
/// Space around the axis titles and at the open sides of a panel (pixels).
const GAP: i32 = 6;
const MARGIN_TOP: i32 = 12;
const MARGIN_RIGHT: i32 = 28;

/// A built chart panel.
pub(crate) type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<AxisCoord, AxisCoord>>;

/// What a panel shows along its axes.
pub(crate) struct PanelAxes {
    pub(crate) x: AxisCoord,
    pub(crate) y: AxisCoord,
    /// Axis titles; an empty x title (a panel above another that shares x) takes no room.
    pub(crate) x_title: String,
    pub(crate) y_title: String,
    /// Scales, to tell which points can be drawn.
    pub(crate) x_scale: Scale,
    pub(crate) y_scale: Scale,
    /// Least width of the room left of the panel for y tick labels and title (pixels), so
    /// that panels stacked above each other line up.
    pub(crate) min_y_room: i32,
}

impl PanelAxes {
    /// Axes with these ranges, titles and scales.
    pub(crate) fn new(
        (x, y): (AxisCoord, AxisCoord),
        (x_title, y_title): (String, String),
        (x_scale, y_scale): (Scale, Scale),
    ) -> Self {
        PanelAxes {
            x,
            y,
            x_title,
            y_title,
            x_scale,
            y_scale,
            min_y_room: 0,
        }
    }
}

/// Width of the room left of a panel for its y tick labels and title (pixels).
pub(crate) fn y_room<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    axes: &PanelAxes,
) -> Result<i32, PlotError> {
    let tick_style = style::text(TICK_EM);
    let mut widest_label = 0u32;
    for (_, label) in axes.y.labelled_ticks(MAX_MAJOR_TICKS) {
        widest_label = widest_label.max(area.estimate_text_size(&label, &tick_style)?.0);
    }
    let (_, title_height) = area.estimate_text_size("0", &style::text(AXIS_TITLE_EM))?;
    let title_room = if axes.y_title.is_empty() {
        0
    } else {
        title_height as i32 + GAP
    };
    Ok((widest_label as i32 + 2 * TICK_MARK + GAP + title_room).max(axes.min_y_room))
}

/// A laid-out panel: the chart, the whole area it was built on (plot, label areas and
/// margins), and its axes. Everything in the plot is drawn on the whole area in pixels, so
/// that a marker on the plot's edge is not cut (plotters clamps each shape's points to the
/// area it is drawn on).
pub(crate) struct Panel<'a, DB: DrawingBackend> {
    pub(crate) chart: Chart<'a, DB>,
    pub(crate) area: &'a DrawingArea<DB, Shift>,
    pub(crate) axes: PanelAxes,
}

impl<DB: DrawingBackend> Panel<'_, DB> {
    /// Pixel position of a data point, relative to the panel's area.
    pub(crate) fn to_pixel(&self, x: f64, y: f64) -> (i32, i32) {
        let (bx, by) = self.chart.backend_coord(&(x, y));
        let (ox, oy) = self.area.get_base_pixel();
        (bx - ox, by - oy)
    }

    /// The plot (inside the axes), in pixels of the panel's area.
    pub(crate) fn plot_rect(&self) -> Rect {
        let plot = self.chart.plotting_area();
        let (px, py) = plot.get_base_pixel();
        let (ox, oy) = self.area.get_base_pixel();
        let (w, h) = plot.dim_in_pixel();
        let (x0, y0) = (px - ox, py - oy);
        Rect {
            x0,
            y0,
            x1: x0 + w as i32,
            y1: y0 + h as i32,
        }
    }

    /// Size of the plot in pixels.
    pub(crate) fn plot_size(&self) -> (u32, u32) {
        self.chart.plotting_area().dim_in_pixel()
    }

    /// Draws the grid, axes, tick labels and titles (for panels made with [`layout`]).
    pub(crate) fn draw_mesh(&mut self) -> Result<(), PlotError> {
        let mut mesh = self.chart.configure_mesh();
        mesh.x_labels(MAX_MAJOR_TICKS)
            .y_labels(MAX_MAJOR_TICKS)
            .max_light_lines(MAX_MAJOR_TICKS)
            .light_line_style(GRID_MINOR)
            .bold_line_style(GRID_MAJOR)
            .axis_style(INK)
            .set_all_tick_mark_size(TICK_MARK)
            .label_style(style::text(TICK_EM))
            .axis_desc_style(style::text(AXIS_TITLE_EM));
        if !self.axes.x_title.is_empty() {
            mesh.x_desc(self.axes.x_title.as_str());
        }
        if !self.axes.y_title.is_empty() {
            mesh.y_desc(self.axes.y_title.as_str());
        }
        mesh.draw()?;
        Ok(())
    }

    /// Draws the points as a line, broken wherever a point cannot be drawn (not finite, or
    /// not positive on a log axis) and wherever `breaks_before(i)` says so; a stretch of one
    /// point is drawn as a dot. Returns whether anything was drawn.
    pub(crate) fn draw_curve(
        &self,
        points: &[(f64, f64)],
        stroke: &Stroke,
        breaks_before: impl Fn(usize) -> bool,
    ) -> Result<bool, PlotError> {
        let mut drew = false;
        let mut run: Vec<(i32, i32)> = Vec::new();
        let flush = |run: &mut Vec<(i32, i32)>| -> Result<(), PlotError> {
            match run.as_slice() {
                [] => {}
                [single] => {
                    let dot = MarkerStyle::new(
                        style::Marker::Circle,
                        stroke.color,
                        stroke.width.max(2) as i32,
                        true,
                    );
                    draw_pixel_marker(self.area, *single, &dot)?;
                }
                line => draw_pixel_line(self.area, line, stroke)?,
            }
            run.clear();
            Ok(())
        };
        for (index, &(x, y)) in points.iter().enumerate() {
            let ok = self.drawable(x, y);
            if !ok || breaks_before(index) {
                flush(&mut run)?;
            }
            if ok {
                run.push(self.to_pixel(x, y));
                drew = true;
            }
        }
        flush(&mut run)?;
        Ok(drew)
    }

    /// Draws a marker at every drawable point; returns how many were drawn.
    pub(crate) fn draw_markers(
        &self,
        points: &[(f64, f64)],
        marker: &MarkerStyle,
    ) -> Result<usize, PlotError> {
        let mut count = 0;
        for &(x, y) in points {
            if self.drawable(x, y) {
                draw_pixel_marker(self.area, self.to_pixel(x, y), marker)?;
                count += 1;
            }
        }
        Ok(count)
    }

    /// Draws each curve's line (broken at undrawable points) and markers.
    pub(crate) fn draw_curves(&self, curves: &[&Curve]) -> Result<(), PlotError> {
        for curve in curves {
            self.draw_curve(&curve.points, &curve.stroke, |_| false)?;
            if let Some(marker) = &curve.marker {
                self.draw_markers(&curve.points, marker)?;
            }
        }
        Ok(())
    }

    fn drawable(&self, x: f64, y: f64) -> bool {
        drawable(x, self.axes.x_scale) && drawable(y, self.axes.y_scale)
    }
}

/// Builds the panel on `area` and draws its grid, axes, tick labels and titles.
pub(crate) fn build<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    axes: PanelAxes,
) -> Result<Panel<'a, DB>, PlotError> {
    let mut panel = layout(area, axes)?;
    panel.draw_mesh()?;
    Ok(panel)
}

/// Lays the panel out on `area` (room for tick labels and titles) without drawing anything.
pub(crate) fn layout<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    axes: PanelAxes,
) -> Result<Panel<'a, DB>, PlotError> {
    let (_, tick_height) = area.estimate_text_size("0", &style::text(TICK_EM))?;
    let (_, title_height) = area.estimate_text_size("0", &style::text(AXIS_TITLE_EM))?;
    let x_title_room = if axes.x_title.is_empty() {
        0
    } else {
        title_height as i32 + GAP
    };
    let y_area = y_room(area, &axes)?;
    let x_area = tick_height as i32 + 2 * TICK_MARK + GAP + x_title_room;
    let chart = ChartBuilder::on(area)
        .margin_top(MARGIN_TOP)
        .margin_right(MARGIN_RIGHT)
        .margin_left(GAP)
        .x_label_area_size(x_area)
        .y_label_area_size(y_area)
        .build_cartesian_2d(axes.x.clone(), axes.y.clone())?;
    Ok(Panel { chart, area, axes })
}

/// A named line (and optionally markers) through points, as the curve figures draw it.
#[derive(Debug, Clone)]
pub(crate) struct Curve {
    pub(crate) label: String,
    pub(crate) points: Vec<(f64, f64)>,
    pub(crate) stroke: Stroke,
    pub(crate) marker: Option<MarkerStyle>,
}

impl Curve {
    /// Whether any point can be drawn on these scales.
    pub(crate) fn has_drawable(&self, x_scale: Scale, y_scale: Scale) -> bool {
        self.points
            .iter()
            .any(|&(x, y)| drawable(x, x_scale) && drawable(y, y_scale))
    }

    /// The legend line for this curve; a curve with nothing to draw says so.
    pub(crate) fn legend(&self, x_scale: Scale, y_scale: Scale) -> style::LegendEntry {
        let label = if self.has_drawable(x_scale, y_scale) {
            self.label.clone()
        } else {
            format!("{} (nothing to draw)", self.label)
        };
        style::LegendEntry {
            label,
            stroke: Some(self.stroke),
            marker: self.marker,
        }
    }
}

/// Axes that show every point (of every curve) drawable on both scales, padded by the given
/// fractions; `None` when there is no such point.
pub(crate) fn fit_axes(
    curves: &[&Curve],
    (x_scale, y_scale): (Scale, Scale),
    (x_pad, y_pad): (f64, f64),
) -> Option<(AxisCoord, AxisCoord)> {
    let both = || {
        curves
            .iter()
            .flat_map(|c| c.points.iter())
            .filter(move |&&(x, y)| drawable(x, x_scale) && drawable(y, y_scale))
    };
    let x = AxisCoord::fit(both().map(|p| p.0), x_scale, x_pad)?;
    let y = AxisCoord::fit(both().map(|p| p.1), y_scale, y_pad)?;
    Some((x, y))
}

/// Titles and scales of a single-panel curve figure.
pub(crate) struct CurveFigure<'a> {
    pub(crate) figure: &'static str,
    pub(crate) title: &'a str,
    pub(crate) x_title: String,
    pub(crate) y_title: String,
    pub(crate) scales: (Scale, Scale),
    /// Range padding, as fractions of the span (of log10 on log axes).
    pub(crate) pads: (f64, f64),
}

/// Draws a titled single-panel figure of curves with the legend on the right; curves are
/// drawn in order (later ones on top), the legend lists them in `legend_order`.
pub(crate) fn draw_curve_figure<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    spec: &CurveFigure<'_>,
    curves: &[&Curve],
    legend_order: &[&Curve],
) -> Result<(), PlotError> {
    let (x, y) =
        fit_axes(curves, spec.scales, spec.pads).ok_or_else(|| PlotError::NothingToPlot {
            figure: spec.figure,
            reason: no_drawable_point(spec.scales),
        })?;
    let axes = PanelAxes::new(
        (x, y),
        (spec.x_title.clone(), spec.y_title.clone()),
        spec.scales,
    );
    let entries: Vec<_> = legend_order
        .iter()
        .map(|c| c.legend(spec.scales.0, spec.scales.1))
        .collect();
    let body = style::draw_title(area, spec.title, None)?;
    let (chart_area, legend_area) = style::split_for_legend(&body, &entries, 0.35)?;
    let panel = build(&chart_area, axes)?;
    panel.draw_curves(curves)?;
    if let Some(legend_area) = legend_area {
        style::draw_legend(&legend_area, &entries, MARGIN_TOP)?;
    }
    Ok(())
}

/// Why a figure with points has none to draw, for its error message.
pub(crate) fn no_drawable_point((x_scale, y_scale): (Scale, Scale)) -> String {
    let positive = match (x_scale, y_scale) {
        (Scale::Linear, Scale::Linear) => "",
        (Scale::Log, Scale::Linear) => " with x positive (log axis)",
        (Scale::Linear, Scale::Log) => " with y positive (log axis)",
        (Scale::Log, Scale::Log) => " with x and y positive (log axes)",
    };
    format!("no point has finite coordinates{positive}")
}
