//! The speed–accuracy trade-off: time against error of model variants, with the Pareto
//! front (the variants no other variant beats in both) marked.

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::axis::{AxisCoord, Scale, axis_label, fit_range};
use crate::chart::{self, PanelAxes};
use crate::labels::{Label, LabelPlacer, Rect, Side};
use crate::style::{
    self, ANNOTATION_EM, Dash, HIGHLIGHT, INK, LegendEntry, Marker, MarkerStyle, PALETTE, Stroke,
};
use crate::{Figure, PlotError};

const FIGURE: &str = "trade-off chart";

/// One model variant: how long it took and how far its answer is from the reference.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TradeoffPoint {
    /// Variant name, written next to its point.
    pub name: String,
    /// Time to answer (s), > 0.
    pub seconds: f64,
    /// Largest relative error against the reference, >= 0; exactly 0 for the reference
    /// itself (drawn at the bottom edge of the chart).
    pub max_relative_error: f64,
}

impl TradeoffPoint {
    /// A variant's time (s) and error.
    pub fn new(name: impl Into<String>, seconds: f64, max_relative_error: f64) -> Self {
        TradeoffPoint {
            name: name.into(),
            seconds,
            max_relative_error,
        }
    }
}

/// Indices of the points on the Pareto front, fastest first: those for which no other
/// point is at least as fast and at least as accurate and strictly better in one of the
/// two. Points with a time or error that is not finite take no part.
pub fn pareto_front(points: &[TradeoffPoint]) -> Vec<usize> {
    let valid = |p: &TradeoffPoint| p.seconds.is_finite() && p.max_relative_error.is_finite();
    let dominates = |a: &TradeoffPoint, b: &TradeoffPoint| {
        a.seconds <= b.seconds
            && a.max_relative_error <= b.max_relative_error
            && (a.seconds < b.seconds || a.max_relative_error < b.max_relative_error)
    };
    let mut front: Vec<usize> = (0..points.len())
        .filter(|&i| {
            let p = &points[i];
            valid(p) && !points.iter().any(|q| valid(q) && dominates(q, p))
        })
        .collect();
    front.sort_by(|&a, &b| {
        let (p, q) = (&points[a], &points[b]);
        p.seconds
            .total_cmp(&q.seconds)
            .then(p.max_relative_error.total_cmp(&q.max_relative_error))
    });
    front
}

/// Log time (s) against log error, one labelled point per variant, the Pareto front joined
/// and filled in, variants with zero error (the reference) on the bottom edge, and an
/// optional tolerance line.
///
/// Every time must be finite and positive and every error finite and non-negative: anything
/// else is an error naming the variant.
#[derive(Debug, Clone, PartialEq)]
pub struct TradeoffChart {
    /// Figure title (may be empty).
    pub title: String,
    /// The variants.
    pub points: Vec<TradeoffPoint>,
    /// What the error is, for the y axis (default `"max relative error"`).
    pub error_quantity: String,
    /// A tolerance to draw as a horizontal dashed line (relative error), if any.
    pub tolerance: Option<f64>,
    /// Width and height, pixels (default 960 x 640).
    pub size: (u32, u32),
}

impl TradeoffChart {
    /// A chart of these variants.
    pub fn new(title: impl Into<String>, points: Vec<TradeoffPoint>) -> Self {
        TradeoffChart {
            title: title.into(),
            points,
            error_quantity: "max relative error".to_string(),
            tolerance: None,
            size: (960, 640),
        }
    }

    fn validate(&self) -> Result<(), PlotError> {
        if self.points.is_empty() {
            return Err(PlotError::NothingToPlot {
                figure: FIGURE,
                reason: "no variants".to_string(),
            });
        }
        for p in &self.points {
            let checks = [
                (
                    "seconds",
                    p.seconds,
                    p.seconds > 0.0,
                    "must be > 0 (log axis)",
                ),
                (
                    "max relative error",
                    p.max_relative_error,
                    p.max_relative_error >= 0.0,
                    "must be >= 0",
                ),
            ];
            for (what, value, ok, reason) in checks {
                let what = format!("{what} of variant `{}`", p.name);
                if !value.is_finite() {
                    return Err(PlotError::NotFinite {
                        figure: FIGURE,
                        what,
                        value,
                    });
                }
                if !ok {
                    return Err(PlotError::InvalidInput {
                        figure: FIGURE,
                        what,
                        reason: format!("{value} {reason}"),
                    });
                }
            }
        }
        if let Some(tolerance) = self.tolerance
            && !(tolerance.is_finite() && tolerance > 0.0)
        {
            return Err(PlotError::InvalidInput {
                figure: FIGURE,
                what: "tolerance".to_string(),
                reason: format!("{tolerance} must be finite and > 0 (log axis)"),
            });
        }
        Ok(())
    }

    /// Axes: time over every variant; error over the positive errors and the tolerance
    /// (a decade down to 1 when there is none of either).
    fn axes(&self) -> Option<PanelAxes> {
        let x = AxisCoord::fit(self.points.iter().map(|p| p.seconds), Scale::Log, 0.08)?;
        let errors = self
            .points
            .iter()
            .map(|p| p.max_relative_error)
            .chain(self.tolerance);
        let (lo, hi) = fit_range(errors, Scale::Log, 0.08).unwrap_or((1e-1, 1.0));
        let y = AxisCoord::fit([lo, hi], Scale::Log, 0.0)?;
        Some(PanelAxes::new(
            (x, y),
            (axis_label("time", "s"), self.error_quantity.clone()),
            (Scale::Log, Scale::Log),
        ))
    }
}

const VARIANT: MarkerStyle = MarkerStyle {
    marker: Marker::Circle,
    color: PALETTE[0],
    size: 5,
    filled: false,
};
const ON_FRONT: MarkerStyle = MarkerStyle {
    marker: Marker::Circle,
    color: HIGHLIGHT,
    size: 6,
    filled: true,
};
const ZERO_ERROR: MarkerStyle = MarkerStyle {
    marker: Marker::Square,
    color: INK,
    size: 6,
    filled: false,
};

impl Figure for TradeoffChart {
    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        self.validate()?;
        let axes = self.axes().ok_or_else(|| PlotError::NothingToPlot {
            figure: FIGURE,
            reason: "no drawable variant".to_string(),
        })?;
        let front = pareto_front(&self.points);
        let bottom = axes.y.bounds().0;
        // Zero error sits on the bottom edge.
        let shown = |p: &TradeoffPoint| {
            let error = if p.max_relative_error > 0.0 {
                p.max_relative_error
            } else {
                bottom
            };
            (p.seconds, error)
        };
        let front_stroke = Stroke::solid(HIGHLIGHT, 2);
        let tolerance_stroke = Stroke {
            color: PALETTE[7],
            width: 2,
            dash: Dash::Dashed,
        };

        let mut entries = vec![
            LegendEntry {
                label: "variant".to_string(),
                stroke: None,
                marker: Some(VARIANT),
            },
            LegendEntry {
                label: "Pareto front (no other variant both faster and more accurate)".to_string(),
                stroke: Some(front_stroke),
                marker: Some(ON_FRONT),
            },
        ];
        if self.points.iter().any(|p| p.max_relative_error == 0.0) {
            entries.push(LegendEntry {
                label: "zero error (the reference): drawn on the bottom edge".to_string(),
                stroke: None,
                marker: Some(ZERO_ERROR),
            });
        }
        if let Some(tolerance) = self.tolerance {
            entries.push(LegendEntry {
                label: format!("tolerance {}", crate::axis::format_number(tolerance, 3)),
                stroke: Some(tolerance_stroke),
                marker: None,
            });
        }

        let body = style::draw_title(area, &self.title, None)?;
        let (chart_area, legend) = style::split_for_legend(&body, &entries, 0.3)?;
        let (x0, x1) = axes.x.bounds();
        let panel = chart::build(&chart_area, axes)?;
        if let Some(tolerance) = self.tolerance {
            panel.draw_curve(
                &[(x0, tolerance), (x1, tolerance)],
                &tolerance_stroke,
                |_| false,
            )?;
        }
        let front_points: Vec<(f64, f64)> = front.iter().map(|&i| shown(&self.points[i])).collect();
        panel.draw_curve(&front_points, &front_stroke, |_| false)?;

        let mut placer = LabelPlacer::new(panel.plot_rect());
        let mut placed = Vec::with_capacity(self.points.len());
        for (index, point) in self.points.iter().enumerate() {
            let (x, y) = shown(point);
            let at = panel.to_pixel(x, y);
            let marker = if front.contains(&index) {
                ON_FRONT
            } else {
                VARIANT
            };
            style::draw_pixel_marker(panel.area, at, &marker)?;
            if point.max_relative_error == 0.0 {
                style::draw_pixel_marker(panel.area, at, &ZERO_ERROR)?;
            }
            placer.block(Rect::around(at, ZERO_ERROR.size + 1));
            placed.push(at);
        }
        let label_style = style::text(ANNOTATION_EM);
        for (point, at) in self.points.iter().zip(placed) {
            let label = Label {
                text: &point.name,
                style: &label_style,
                at,
                gap: ZERO_ERROR.size + 3,
            };
            placer.place(panel.area, &label, &Side::ALL, true)?;
        }
        if let Some(legend) = legend {
            style::draw_legend(&legend, &entries, 12)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hand-worked front. Points (s, error):
    ///   a (1, 0.1)   fastest: nothing is faster, so nothing dominates it -> front
    ///   b (2, 0.1)   a is faster with the same error -> dominated
    ///   c (2, 0.01)  only a is faster, and a is less accurate -> front
    ///   d (3, 0.05)  c is faster and more accurate -> dominated
    ///   e (5, 0)     the most accurate (zero error) -> front
    ///   f (5, 0)     same as e: neither is strictly better -> front
    ///   g (9, 0.001) e is faster and more accurate -> dominated
    ///   h (NaN, 0)   not finite: takes no part (and does not dominate e or f)
    /// Front, fastest first: a, c, e, f.
    #[test]
    fn pareto_front_matches_the_hand_worked_example() {
        let points: Vec<TradeoffPoint> = [
            ("a", 1.0, 0.1),
            ("b", 2.0, 0.1),
            ("c", 2.0, 0.01),
            ("d", 3.0, 0.05),
            ("e", 5.0, 0.0),
            ("f", 5.0, 0.0),
            ("g", 9.0, 0.001),
            ("h", f64::NAN, 0.0),
        ]
        .into_iter()
        .map(|(name, s, e)| TradeoffPoint::new(name, s, e))
        .collect();
        let front: Vec<&str> = pareto_front(&points)
            .into_iter()
            .map(|i| points[i].name.as_str())
            .collect();
        assert_eq!(front, ["a", "c", "e", "f"]);
    }

    #[test]
    fn pareto_front_of_nothing_or_one() {
        assert!(pareto_front(&[]).is_empty());
        assert_eq!(
            pareto_front(&[TradeoffPoint::new("only", 1.0, 0.5)]),
            vec![0]
        );
    }
}
