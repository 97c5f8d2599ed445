//! A generic multi-series line plot, for sweeps: values against a swept parameter.

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::axis::Axis;
use crate::chart::{self, Curve, CurveFigure};
use crate::style::{Marker, MarkerStyle, Stroke};
use crate::{Figure, PlotError};

const FIGURE: &str = "line plot";

/// One named series: `y[i]` against `x[i]`, in the units of the plot's axes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Series {
    /// Legend name.
    pub name: String,
    /// Abscissae (the swept values).
    pub x: Vec<f64>,
    /// Ordinates, as many as `x`.
    pub y: Vec<f64>,
}

impl Series {
    /// A series from its name and values.
    pub fn new(name: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Series {
            name: name.into(),
            x,
            y,
        }
    }
}

/// Several series against one swept parameter, on linear or logarithmic axes.
///
/// Points that cannot be drawn (not finite, or not positive on a log axis) are skipped and
/// break the line; no series, or no drawable point at all, is an error (see the crate
/// documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct LinePlot {
    /// Figure title (may be empty).
    pub title: String,
    /// Horizontal axis: the swept parameter.
    pub x: Axis,
    /// Vertical axis: the values.
    pub y: Axis,
    /// The series, drawn in order, each in the next colour.
    pub series: Vec<Series>,
    /// Mark every point as well as joining them (useful for coarse sweeps).
    pub markers: bool,
    /// Width and height, pixels (default 960 x 600).
    pub size: (u32, u32),
}

impl LinePlot {
    /// An empty plot with these axes; push series onto [`LinePlot::series`].
    pub fn new(title: impl Into<String>, x: Axis, y: Axis) -> Self {
        LinePlot {
            title: title.into(),
            x,
            y,
            series: Vec::new(),
            markers: false,
            size: (960, 600),
        }
    }

    /// Checks the series and turns them into curves.
    fn curves(&self) -> Result<Vec<Curve>, PlotError> {
        if self.series.is_empty() {
            return Err(PlotError::NothingToPlot {
                figure: FIGURE,
                reason: "no series".to_string(),
            });
        }
        self.series
            .iter()
            .enumerate()
            .map(|(index, series)| {
                if series.x.len() != series.y.len() {
                    return Err(PlotError::LengthMismatch {
                        figure: FIGURE,
                        what: format!("y of series `{}`", series.name),
                        expected: series.x.len(),
                        found: series.y.len(),
                    });
                }
                let stroke = Stroke::series(index, 2);
                Ok(Curve {
                    label: series.name.clone(),
                    points: series
                        .x
                        .iter()
                        .copied()
                        .zip(series.y.iter().copied())
                        .collect(),
                    stroke,
                    marker: self
                        .markers
                        .then(|| MarkerStyle::new(Marker::Circle, stroke.color, 3, true)),
                })
            })
            .collect()
    }
}

impl Figure for LinePlot {
    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let curves = self.curves()?;
        let refs: Vec<&Curve> = curves.iter().collect();
        let spec = CurveFigure {
            figure: FIGURE,
            title: &self.title,
            x_title: self.x.label(),
            y_title: self.y.label(),
            scales: (self.x.scale, self.y.scale),
            pads: (0.02, 0.05),
        };
        chart::draw_curve_figure(area, &spec, &refs, &refs)
    }
}
