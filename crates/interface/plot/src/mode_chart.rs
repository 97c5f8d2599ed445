//! Mode chart: mode frequencies as markers on a log frequency axis, one row per
//! degree-of-freedom family.

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::axis::{AxisCoord, Scale, axis_label, format_number};
use crate::chart::{self, PanelAxes};
use crate::labels::{Label, LabelPlacer, Rect, Side};
use crate::style::{self, ANNOTATION_EM, HIGHLIGHT, LegendEntry, Marker, MarkerStyle, PALETTE};
use crate::{Figure, PlotError};

const FIGURE: &str = "mode chart";

/// Row order used when [`ModeChart::family_order`] is left at its default: LIGO's degrees
/// of freedom (L = x, T = y, V = z, R = roll, P = pitch, Y = yaw), then violin modes and
/// anything else.
pub const DEFAULT_FAMILY_ORDER: [&str; 8] = ["L", "T", "V", "R", "P", "Y", "violin", "other"];

/// One mode of a [`ModeChart`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ModeMarker {
    /// Frequency (Hz) of a stable mode, > 0; for an unstable mode its growth rate
    /// sqrt(-ω²)/2π (Hz), either sign (pendkit lists unstable modes at minus their growth
    /// rate).
    pub frequency_hz: f64,
    /// Degree-of-freedom family: the row the mode goes in (e.g. `"P"`, `"violin"`).
    pub family: String,
    /// Text written next to the marker; `None` writes the frequency (3 digits), an empty
    /// string writes nothing.
    pub label: Option<String>,
    /// An unstable mode, plotted at its growth rate with a distinct marker.
    pub unstable: bool,
}

impl ModeMarker {
    /// A stable mode at `frequency_hz` in `family`, labelled with its frequency.
    pub fn new(frequency_hz: f64, family: impl Into<String>) -> Self {
        ModeMarker {
            frequency_hz,
            family: family.into(),
            label: None,
            unstable: false,
        }
    }
}

/// Mode frequencies (log axis) as markers in rows by degree-of-freedom family, each
/// labelled where its label fits without overlapping another (labels that do not fit are
/// left out; the markers never are). Unstable modes are red crosses at their growth rate.
///
/// A frequency that is not finite is an error naming the mode; modes at exactly 0 Hz cannot
/// be placed on the log axis and are counted under the title instead.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeChart {
    /// Figure title (may be empty).
    pub title: String,
    /// The modes, in any order.
    pub modes: Vec<ModeMarker>,
    /// Families in row order, top first; families of the modes that are not listed follow
    /// in order of first appearance, and listed families without modes get no row.
    pub family_order: Vec<String>,
    /// Width and height, pixels (default 960 x 560).
    pub size: (u32, u32),
}

impl ModeChart {
    /// A chart of these modes with the default row order ([`DEFAULT_FAMILY_ORDER`]).
    pub fn new(title: impl Into<String>, modes: Vec<ModeMarker>) -> Self {
        ModeChart {
            title: title.into(),
            modes,
            family_order: DEFAULT_FAMILY_ORDER.iter().map(|s| s.to_string()).collect(),
            size: (960, 560),
        }
    }

    fn validate(&self) -> Result<(), PlotError> {
        if self.modes.is_empty() {
            return Err(PlotError::NothingToPlot {
                figure: FIGURE,
                reason: "no modes".to_string(),
            });
        }
        for (index, mode) in self.modes.iter().enumerate() {
            let what = || format!("frequency of mode {index} ({})", mode.family);
            if !mode.frequency_hz.is_finite() {
                return Err(PlotError::NotFinite {
                    figure: FIGURE,
                    what: what(),
                    value: mode.frequency_hz,
                });
            }
            if mode.frequency_hz < 0.0 && !mode.unstable {
                return Err(PlotError::InvalidInput {
                    figure: FIGURE,
                    what: what(),
                    reason: format!(
                        "{} Hz is negative for a stable mode (mark a mode given by its growth rate as unstable)",
                        mode.frequency_hz
                    ),
                });
            }
        }
        Ok(())
    }

    /// Families that have modes, in row order.
    fn rows(&self) -> Vec<&str> {
        let present = |family: &str| self.modes.iter().any(|m| m.family == family);
        let mut rows: Vec<&str> = Vec::new();
        for family in &self.family_order {
            if present(family) && !rows.contains(&family.as_str()) {
                rows.push(family);
            }
        }
        for mode in &self.modes {
            if !rows.contains(&mode.family.as_str()) {
                rows.push(&mode.family);
            }
        }
        rows
    }

    /// The legend: the stable marker, and the unstable one when any mode is unstable.
    fn legend_entries(&self) -> Vec<LegendEntry> {
        let mut entries = vec![LegendEntry {
            label: "mode (label: frequency, Hz)".to_string(),
            stroke: None,
            marker: Some(stable_marker(0)),
        }];
        if self.modes.iter().any(|m| m.unstable) {
            entries.push(LegendEntry {
                label: "unstable mode, at its growth rate (Hz)".to_string(),
                stroke: None,
                marker: Some(UNSTABLE),
            });
        }
        entries
    }
}

const UNSTABLE: MarkerStyle = MarkerStyle {
    marker: Marker::Cross,
    color: HIGHLIGHT,
    size: 6,
    filled: false,
};

fn stable_marker(row: usize) -> MarkerStyle {
    MarkerStyle::new(Marker::Circle, PALETTE[row % PALETTE.len()], 5, true)
}

impl Figure for ModeChart {
    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        self.validate()?;
        let rows = self.rows();
        let row_of = |family: &str| rows.iter().position(|r| *r == family).unwrap_or(0);
        // Row 0 at the top.
        let y_of = |row: usize| (rows.len() - 1 - row) as f64;
        let zero_count = self.modes.iter().filter(|m| m.frequency_hz == 0.0).count();
        let x = AxisCoord::fit(
            self.modes.iter().map(|m| m.frequency_hz.abs()),
            Scale::Log,
            0.05,
        )
        .ok_or_else(|| PlotError::NothingToPlot {
            figure: FIGURE,
            reason: "every mode is at 0 Hz".to_string(),
        })?;
        let ticks = (0..rows.len())
            .map(|row| (y_of(row), rows[row].to_string()))
            .collect();
        let y = AxisCoord::linear(-0.5, rows.len() as f64 - 0.5)
            .map(|axis| axis.with_ticks(ticks))
            .ok_or_else(|| PlotError::NothingToPlot {
                figure: FIGURE,
                reason: "no rows".to_string(),
            })?;
        let axes = PanelAxes::new(
            (x, y),
            (
                axis_label("frequency", "Hz"),
                "degree of freedom".to_string(),
            ),
            (Scale::Log, Scale::Linear),
        );

        let entries = self.legend_entries();
        let note = (zero_count > 0).then(|| {
            let s = if zero_count == 1 { "" } else { "s" };
            format!("{zero_count} mode{s} at 0 Hz not shown (log axis)")
        });
        let body = style::draw_title(area, &self.title, note.as_deref())?;
        let (chart_area, legend) = style::split_for_legend(&body, &entries, 0.3)?;
        let panel = chart::build(&chart_area, axes)?;
        let mut placer = LabelPlacer::new(panel.plot_rect());
        // Markers first (labels must avoid all of them), lowest frequency first.
        let mut order: Vec<usize> = (0..self.modes.len()).collect();
        order.sort_by(|&a, &b| {
            let (fa, fb) = (
                self.modes[a].frequency_hz.abs(),
                self.modes[b].frequency_hz.abs(),
            );
            fa.total_cmp(&fb)
        });
        let mut drawn = Vec::new();
        for &index in &order {
            let mode = &self.modes[index];
            let f = mode.frequency_hz.abs();
            if f == 0.0 {
                continue;
            }
            let row = row_of(&mode.family);
            let at = panel.to_pixel(f, y_of(row));
            let marker = if mode.unstable {
                UNSTABLE
            } else {
                stable_marker(row)
            };
            style::draw_pixel_marker(panel.area, at, &marker)?;
            placer.block(Rect::around(at, marker.size + 1));
            drawn.push((index, at));
        }
        let label_style = style::text(ANNOTATION_EM);
        for (index, at) in drawn {
            let mode = &self.modes[index];
            let text = mode
                .label
                .clone()
                .unwrap_or_else(|| format_number(mode.frequency_hz.abs(), 3));
            let label = Label {
                text: &text,
                style: &label_style,
                at,
                gap: UNSTABLE.size + 2,
            };
            // Centred above or below; shifted right or left near the plot's edges.
            let sides = [
                Side::Above,
                Side::Below,
                Side::AboveRight,
                Side::BelowRight,
                Side::AboveLeft,
                Side::BelowLeft,
            ];
            placer.place(panel.area, &label, &sides, false)?;
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

    #[test]
    fn rows_follow_the_given_order_then_first_appearance() {
        let modes = ["violin", "P", "Q", "L", "P", "Z"]
            .iter()
            .map(|f| ModeMarker::new(1.0, *f))
            .collect();
        let chart = ModeChart::new("", modes);
        assert_eq!(chart.rows(), ["L", "P", "violin", "Q", "Z"]);
    }
}
