//! Noise budget: the amplitude spectral density of a total and of its named contributions.

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::axis::{Scale, axis_label};
use crate::chart::{self, Curve, CurveFigure};
use crate::style::{INK, Stroke};
use crate::{Figure, PlotError};

const FIGURE: &str = "noise budget";

/// One named curve of a noise budget: ASD values at the budget's frequencies.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Contribution {
    /// Legend name, e.g. a damping tag (`"fibre_bending"`) or `"total"`.
    pub name: String,
    /// ASD at each frequency of the budget, in the budget's unit.
    pub asd: Vec<f64>,
}

impl Contribution {
    /// A named ASD curve.
    pub fn new(name: impl Into<String>, asd: Vec<f64>) -> Self {
        Contribution {
            name: name.into(),
            asd,
        }
    }
}

/// A noise budget, log-log: the total as a thick black line on top of its contributions,
/// each thinner and in its own colour.
///
/// The y axis reads `quantity (unit)`, e.g. `displacement ASD (m/√Hz)`; zeros, NaNs and
/// non-positive frequencies are skipped (see the crate documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct NoiseBudget {
    /// Figure title (may be empty).
    pub title: String,
    /// What is plotted, e.g. `"displacement ASD"`.
    pub quantity: String,
    /// Its unit, e.g. `"m/√Hz"`.
    pub unit: String,
    /// Frequencies (Hz) shared by every curve.
    pub frequency_hz: Vec<f64>,
    /// The total.
    pub total: Contribution,
    /// The contributions (e.g. one per damping tag), in legend order.
    pub contributions: Vec<Contribution>,
    /// Width and height, pixels (default 960 x 640).
    pub size: (u32, u32),
}

impl NoiseBudget {
    /// A budget of `total` at `frequency_hz`, with no contributions yet; push them onto
    /// [`NoiseBudget::contributions`].
    pub fn new(
        title: impl Into<String>,
        quantity: impl Into<String>,
        unit: impl Into<String>,
        frequency_hz: Vec<f64>,
        total: Contribution,
    ) -> Self {
        NoiseBudget {
            title: title.into(),
            quantity: quantity.into(),
            unit: unit.into(),
            frequency_hz,
            total,
            contributions: Vec::new(),
            size: (960, 640),
        }
    }

    fn curve(&self, contribution: &Contribution, stroke: Stroke) -> Result<Curve, PlotError> {
        if contribution.asd.len() != self.frequency_hz.len() {
            return Err(PlotError::LengthMismatch {
                figure: FIGURE,
                what: format!("ASD of `{}`", contribution.name),
                expected: self.frequency_hz.len(),
                found: contribution.asd.len(),
            });
        }
        Ok(Curve {
            label: contribution.name.clone(),
            points: self
                .frequency_hz
                .iter()
                .copied()
                .zip(contribution.asd.iter().copied())
                .collect(),
            stroke,
            marker: None,
        })
    }
}

impl Figure for NoiseBudget {
    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        if self.frequency_hz.is_empty() {
            return Err(PlotError::NothingToPlot {
                figure: FIGURE,
                reason: "no frequencies".to_string(),
            });
        }
        let total = self.curve(&self.total, Stroke::solid(INK, 3))?;
        let parts = self
            .contributions
            .iter()
            .enumerate()
            .map(|(index, c)| self.curve(c, Stroke::series(index, 1)))
            .collect::<Result<Vec<_>, _>>()?;
        // Contributions first, the total on top; the legend starts with the total.
        let drawn: Vec<&Curve> = parts.iter().chain(std::iter::once(&total)).collect();
        let legend: Vec<&Curve> = std::iter::once(&total).chain(parts.iter()).collect();
        let spec = CurveFigure {
            figure: FIGURE,
            title: &self.title,
            x_title: axis_label("frequency", "Hz"),
            y_title: axis_label(&self.quantity, &self.unit),
            scales: (Scale::Log, Scale::Log),
            pads: (0.0, 0.05),
        };
        chart::draw_curve_figure(area, &spec, &drawn, &legend)
    }
}
