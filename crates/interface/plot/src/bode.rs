//! Bode plot: magnitude (log-log) and phase (degrees, lin-log) of complex responses.

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::axis::{AxisCoord, Scale, axis_label, drawable, fit_range};
use crate::chart::{self, Curve, PanelAxes};
use crate::style::{self, Stroke};
use crate::{Figure, PlotError};

const FIGURE: &str = "Bode plot";

/// One complex response against frequency, e.g. a transfer function.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BodeSeries {
    /// Legend name, e.g. `"x3/x00"`.
    pub name: String,
    /// Frequencies (Hz).
    pub frequency_hz: Vec<f64>,
    /// (real, imaginary) parts of the response at each frequency, in the plot's unit.
    pub response: Vec<(f64, f64)>,
}

impl BodeSeries {
    /// A series from its name, frequencies (Hz) and (real, imaginary) responses.
    pub fn new(name: impl Into<String>, frequency_hz: Vec<f64>, response: Vec<(f64, f64)>) -> Self {
        BodeSeries {
            name: name.into(),
            frequency_hz,
            response,
        }
    }
}

/// How the phase is shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PhaseDisplay {
    /// In (-180°, 180°], the line broken where it wraps.
    #[default]
    Wrapped,
    /// Continuous: ±360° added wherever consecutive points jump by more than 180°.
    Unwrapped,
}

/// Magnitude (top, log-log) and phase (bottom, degrees against log frequency) of one or
/// more complex responses.
///
/// The magnitude axis reads `quantity (unit)`, e.g. `|x3/x00| (m/m)`. Points with a zero,
/// NaN or infinite magnitude, or a non-positive frequency, are skipped in both panels (the
/// lines break there); see the crate documentation for the rest.
#[derive(Debug, Clone, PartialEq)]
pub struct BodePlot {
    /// Figure title (may be empty).
    pub title: String,
    /// What the magnitude is, e.g. `"|x3/x00|"`.
    pub quantity: String,
    /// Its unit, e.g. `"m/m"` (empty for none).
    pub unit: String,
    /// The responses, each in the next colour.
    pub series: Vec<BodeSeries>,
    /// Wrapped (default) or unwrapped phase.
    pub phase: PhaseDisplay,
    /// Width and height, pixels (default 960 x 720).
    pub size: (u32, u32),
}

impl BodePlot {
    /// An empty Bode plot; push series onto [`BodePlot::series`].
    pub fn new(
        title: impl Into<String>,
        quantity: impl Into<String>,
        unit: impl Into<String>,
    ) -> Self {
        BodePlot {
            title: title.into(),
            quantity: quantity.into(),
            unit: unit.into(),
            series: Vec::new(),
            phase: PhaseDisplay::Wrapped,
            size: (960, 720),
        }
    }
}

/// Magnitude and phase (degrees) curves of one series, phase wrapped or unwrapped; `wraps`
/// lists the indices where a wrapped phase line must break.
struct SeriesCurves {
    magnitude: Curve,
    phase: Curve,
    wraps: Vec<usize>,
}

fn series_curves(
    series: &BodeSeries,
    index: usize,
    display: PhaseDisplay,
) -> Result<SeriesCurves, PlotError> {
    if series.frequency_hz.len() != series.response.len() {
        return Err(PlotError::LengthMismatch {
            figure: FIGURE,
            what: format!("response of series `{}`", series.name),
            expected: series.frequency_hz.len(),
            found: series.response.len(),
        });
    }
    let mut magnitude = Vec::with_capacity(series.response.len());
    let mut phase = Vec::with_capacity(series.response.len());
    let mut wraps = Vec::new();
    let mut previous: Option<f64> = None;
    for (index, (&f, &(re, im))) in series.frequency_hz.iter().zip(&series.response).enumerate() {
        let m = re.hypot(im);
        let usable = drawable(f, Scale::Log) && drawable(m, Scale::Log);
        magnitude.push((f, m));
        if !usable {
            phase.push((f, f64::NAN));
            continue;
        }
        let wrapped = im.atan2(re).to_degrees();
        let shown = match (display, previous) {
            (PhaseDisplay::Unwrapped, Some(last)) => {
                wrapped + 360.0 * ((last - wrapped) / 360.0).round()
            }
            _ => wrapped,
        };
        if let (PhaseDisplay::Wrapped, Some(last)) = (display, previous)
            && (shown - last).abs() > 180.0
        {
            wraps.push(index);
        }
        previous = Some(shown);
        phase.push((f, shown));
    }
    let stroke = Stroke::series(index, 2);
    let curve = |points| Curve {
        label: series.name.clone(),
        points,
        stroke,
        marker: None,
    };
    Ok(SeriesCurves {
        magnitude: curve(magnitude),
        phase: curve(phase),
        wraps,
    })
}

/// The phase axis: ±180° with ticks every 90° when wrapped; fitted to the data otherwise,
/// with ticks every 90° unless that makes too many.
fn phase_axis(curves: &[SeriesCurves], display: PhaseDisplay) -> Option<AxisCoord> {
    let ninety = |lo: f64, hi: f64| -> Vec<(f64, String)> {
        let (first, last) = ((lo / 90.0).ceil() as i64, (hi / 90.0).floor() as i64);
        (first..=last)
            .map(|k| (k as f64 * 90.0, format!("{}", k * 90)))
            .collect()
    };
    match display {
        PhaseDisplay::Wrapped => {
            AxisCoord::linear(-200.0, 200.0).map(|axis| axis.with_ticks(ninety(-180.0, 180.0)))
        }
        PhaseDisplay::Unwrapped => {
            let values = curves
                .iter()
                .flat_map(|c| c.phase.points.iter().map(|p| p.1));
            let (lo, hi) = fit_range(values, Scale::Linear, 0.05)?;
            let axis = AxisCoord::linear(lo, hi)?;
            if (hi - lo) / 90.0 <= chart::MAX_MAJOR_TICKS as f64 {
                Some(axis.with_ticks(ninety(lo, hi)))
            } else {
                Some(axis)
            }
        }
    }
}

impl Figure for BodePlot {
    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        if self.series.is_empty() {
            return Err(PlotError::NothingToPlot {
                figure: FIGURE,
                reason: "no series".to_string(),
            });
        }
        let curves = self
            .series
            .iter()
            .enumerate()
            .map(|(index, series)| series_curves(series, index, self.phase))
            .collect::<Result<Vec<_>, _>>()?;
        let scales = (Scale::Log, Scale::Log);
        let magnitudes: Vec<&Curve> = curves.iter().map(|c| &c.magnitude).collect();
        let nothing = || PlotError::NothingToPlot {
            figure: FIGURE,
            reason: chart::no_drawable_point(scales).replace("x and y", "frequency and magnitude"),
        };
        let (frequency, magnitude) =
            chart::fit_axes(&magnitudes, scales, (0.0, 0.05)).ok_or_else(nothing)?;
        let phase = phase_axis(&curves, self.phase).ok_or_else(nothing)?;

        let entries: Vec<_> = magnitudes
            .iter()
            .map(|c| c.legend(Scale::Log, Scale::Log))
            .collect();
        let body = style::draw_title(area, &self.title, None)?;
        let (charts, legend) = style::split_for_legend(&body, &entries, 0.3)?;
        let (_, height) = charts.dim_in_pixel();
        let (top, bottom) = charts.split_vertically((f64::from(height) * 0.55) as i32);

        let mut magnitude_axes = PanelAxes::new(
            (frequency.clone().without_labels(), magnitude),
            (String::new(), axis_label(&self.quantity, &self.unit)),
            (Scale::Log, Scale::Log),
        );
        let mut phase_axes = PanelAxes::new(
            (frequency, phase),
            (axis_label("frequency", "Hz"), axis_label("phase", "deg")),
            (Scale::Log, Scale::Linear),
        );
        // Both panels get the same room for y labels, so their frequency axes line up.
        let room = chart::y_room(&top, &magnitude_axes)?.max(chart::y_room(&bottom, &phase_axes)?);
        magnitude_axes.min_y_room = room;
        phase_axes.min_y_room = room;

        let magnitude_panel = chart::build(&top, magnitude_axes)?;
        magnitude_panel.draw_curves(&magnitudes)?;
        let phase_panel = chart::build(&bottom, phase_axes)?;
        for curve in &curves {
            phase_panel.draw_curve(&curve.phase.points, &curve.phase.stroke, |i| {
                curve.wraps.binary_search(&i).is_ok()
            })?;
        }
        if let Some(legend) = legend {
            style::draw_legend(&legend, &entries, 12)?;
        }
        Ok(())
    }
}
