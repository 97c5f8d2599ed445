//! Axes: the public [`Axis`] description (quantity, unit, scale), and the one plotters
//! coordinate type every chart uses, [`AxisCoord`], which maps values to pixels on a linear
//! or logarithmic scale, chooses tick positions and formats tick labels.

use std::ops::Range;

use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, Ranged, ValueFormatter};

/// How values map to positions along an axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Scale {
    /// Equal steps of value, equal distances.
    #[default]
    Linear,
    /// Equal ratios of value, equal distances (base 10); only positive values are drawn.
    Log,
}

/// One axis of a [`LinePlot`](crate::LinePlot): what is plotted along it, in which unit,
/// on which scale. The label reads `quantity (unit)`, or the quantity alone when the unit
/// is empty.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Axis {
    /// What the values are, e.g. `"fibre radius"` or `"|x3/x00|"`.
    pub quantity: String,
    /// Their unit, e.g. `"m"`, `"m/√Hz"`; empty for a pure number.
    pub unit: String,
    /// Linear or logarithmic.
    pub scale: Scale,
}

impl Axis {
    /// An axis with the given quantity, unit and scale.
    pub fn new(quantity: impl Into<String>, unit: impl Into<String>, scale: Scale) -> Self {
        Axis {
            quantity: quantity.into(),
            unit: unit.into(),
            scale,
        }
    }

    /// The axis title, `quantity (unit)`.
    pub fn label(&self) -> String {
        axis_label(&self.quantity, &self.unit)
    }
}

/// `quantity (unit)`, or the quantity alone for an empty unit.
pub(crate) fn axis_label(quantity: &str, unit: &str) -> String {
    if unit.is_empty() {
        quantity.to_string()
    } else {
        format!("{quantity} ({unit})")
    }
}

/// Whether a value can be placed on an axis of this scale.
pub(crate) fn drawable(value: f64, scale: Scale) -> bool {
    match scale {
        Scale::Linear => value.is_finite(),
        Scale::Log => value.is_finite() && value > 0.0,
    }
}

/// Pixel coordinates are kept within this distance of the axis: values far outside the range
/// (which the figures do not produce) cannot make the rasteriser sweep millions of pixels.
const MAX_PIXEL_OVERSHOOT: f64 = 1.0e5;

/// At most this many ticks are ever generated on one axis.
const MAX_TICKS: usize = 200;

/// A plotters coordinate along one axis: a finite range on a linear or log scale, with
/// optional fixed ticks and labels (for rows of categories) and optional hidden labels (for
/// a panel that shares its x axis with the one below).
#[derive(Debug, Clone)]
pub(crate) struct AxisCoord {
    /// Range ends in axis units: the values for a linear axis, their log10 for a log axis.
    lo: f64,
    hi: f64,
    scale: Scale,
    /// Ticks to use instead of automatic ones, each with its label.
    fixed_ticks: Option<Vec<(f64, String)>>,
    /// Draw no tick labels (the grid lines stay).
    hide_labels: bool,
}

impl AxisCoord {
    /// An axis from `lo` to `hi` (values), which must be drawable on `scale` with lo < hi.
    /// Callers build ranges with [`fit_range`], which guarantees that.
    fn new(lo: f64, hi: f64, scale: Scale) -> Self {
        let (lo, hi) = match scale {
            Scale::Linear => (lo, hi),
            Scale::Log => (lo.log10(), hi.log10()),
        };
        AxisCoord {
            lo,
            hi,
            scale,
            fixed_ticks: None,
            hide_labels: false,
        }
    }

    /// The axis that shows `values` (those drawable on `scale`), padded by `pad` of its span
    /// at each end; `None` when no value is drawable.
    pub(crate) fn fit(
        values: impl IntoIterator<Item = f64>,
        scale: Scale,
        pad: f64,
    ) -> Option<Self> {
        let (lo, hi) = fit_range(values, scale, pad)?;
        Some(AxisCoord::new(lo, hi, scale))
    }

    /// A linear axis from `lo` to `hi` exactly; `None` unless both are finite and lo < hi.
    pub(crate) fn linear(lo: f64, hi: f64) -> Option<Self> {
        (lo.is_finite() && hi.is_finite() && lo < hi).then(|| AxisCoord::new(lo, hi, Scale::Linear))
    }

    /// The same axis with these ticks and labels instead of automatic ones.
    pub(crate) fn with_ticks(mut self, ticks: Vec<(f64, String)>) -> Self {
        self.fixed_ticks = Some(ticks);
        self
    }

    /// The same axis without tick labels.
    pub(crate) fn without_labels(mut self) -> Self {
        self.hide_labels = true;
        self
    }

    /// Range ends in values.
    pub(crate) fn bounds(&self) -> (f64, f64) {
        (self.value_at(self.lo), self.value_at(self.hi))
    }

    fn axis_units(&self, value: f64) -> f64 {
        match self.scale {
            Scale::Linear => value,
            Scale::Log => value.log10(),
        }
    }

    fn value_at(&self, u: f64) -> f64 {
        match self.scale {
            Scale::Linear => u,
            Scale::Log => 10f64.powf(u),
        }
    }

    /// Fraction of the way from lo to hi (0..1 inside the range); computed on halves so that
    /// ranges spanning most of f64 do not overflow.
    fn fraction(&self, value: f64) -> f64 {
        let u = self.axis_units(value);
        let span = 0.5 * self.hi - 0.5 * self.lo;
        if !u.is_finite() {
            // Zero or negative on a log axis: below the range.
            return if u > 0.0 {
                f64::INFINITY
            } else {
                f64::NEG_INFINITY
            };
        }
        (0.5 * u - 0.5 * self.lo) / span
    }

    /// Tick positions (values): the fixed ones, or automatic ones with at most `major_count`
    /// major ticks, plus minor ticks (at most `max_count` in all) when `with_minor`.
    fn ticks(&self, major_count: usize, max_count: usize, with_minor: bool) -> Vec<f64> {
        if let Some(fixed) = &self.fixed_ticks {
            return fixed.iter().map(|(value, _)| *value).collect();
        }
        let major_count = major_count.clamp(2, MAX_TICKS);
        let max_count = max_count.clamp(major_count, MAX_TICKS);
        match self.scale {
            Scale::Linear => linear_ticks(self.lo, self.hi, major_count, with_minor),
            Scale::Log => log_ticks(self.lo, self.hi, major_count, max_count, with_minor),
        }
    }

    /// Major tick positions and their labels, as the mesh will draw them.
    pub(crate) fn labelled_ticks(&self, max_count: usize) -> Vec<(f64, String)> {
        self.ticks(max_count, max_count, false)
            .into_iter()
            .map(|v| (v, self.label(v)))
            .collect()
    }

    /// The label of one tick.
    fn label(&self, value: f64) -> String {
        if self.hide_labels {
            return String::new();
        }
        if let Some(fixed) = &self.fixed_ticks {
            return fixed
                .iter()
                .find(|(tick, _)| *tick == value)
                .map(|(_, label)| label.clone())
                .unwrap_or_default();
        }
        match self.scale {
            Scale::Linear => format_linear_tick(value, self.lo, self.hi),
            Scale::Log => format_log_tick(value),
        }
    }
}

impl Ranged for AxisCoord {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, (start, end): (i32, i32)) -> i32 {
        let length = f64::from(end) - f64::from(start);
        let offset =
            (self.fraction(*value) * length).clamp(-MAX_PIXEL_OVERSHOOT, MAX_PIXEL_OVERSHOOT);
        let offset = if offset.is_nan() { 0.0 } else { offset };
        (f64::from(start) + offset).round() as i32
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        let with_minor = hint.weight().allow_light_points();
        self.ticks(hint.bold_points(), hint.max_num_points(), with_minor)
    }

    fn range(&self) -> Range<f64> {
        let (lo, hi) = self.bounds();
        lo..hi
    }
}

impl ValueFormatter<f64> for AxisCoord {
    fn format(value: &f64) -> String {
        format_number(*value, 4)
    }

    fn format_ext(&self, value: &f64) -> String {
        self.label(*value)
    }
}

/// The range (lo < hi, both drawable on `scale`) that shows every drawable value, padded by
/// `pad` of the span at each end (in log10 for a log scale). A single value, or values all
/// equal, get a range around them (±10 % or ±1 on a linear scale, half a decade each way on
/// a log scale). `None` when no value is drawable.
pub(crate) fn fit_range(
    values: impl IntoIterator<Item = f64>,
    scale: Scale,
    pad: f64,
) -> Option<(f64, f64)> {
    let mut extent: Option<(f64, f64)> = None;
    for v in values.into_iter().filter(|v| drawable(*v, scale)) {
        extent = Some(match extent {
            None => (v, v),
            Some((lo, hi)) => (lo.min(v), hi.max(v)),
        });
    }
    let (lo, hi) = extent?;
    let pad = if pad.is_finite() { pad.max(0.0) } else { 0.0 };
    match scale {
        Scale::Linear => {
            let (lo, hi) = if lo < hi {
                // On halves so that a span near f64::MAX does not overflow.
                let margin = pad * (0.5 * hi - 0.5 * lo);
                (lo - 2.0 * margin, hi + 2.0 * margin)
            } else if lo == 0.0 {
                (-1.0, 1.0)
            } else {
                (lo - 0.1 * lo.abs(), hi + 0.1 * hi.abs())
            };
            Some((lo.max(-f64::MAX), hi.min(f64::MAX)))
        }
        Scale::Log => {
            let (llo, lhi) = (lo.log10(), hi.log10());
            let (llo, lhi) = if lhi - llo > 1e-9 {
                let margin = pad * (lhi - llo);
                (llo - margin, lhi + margin)
            } else {
                (llo - 0.5, lhi + 0.5)
            };
            // Keep both ends representable as positive finite numbers.
            let (lo, hi) = (10f64.powf(llo), 10f64.powf(lhi));
            let lo = if lo > 0.0 { lo } else { f64::MIN_POSITIVE };
            let hi = if hi.is_finite() { hi } else { f64::MAX };
            (lo < hi).then_some((lo, hi))
        }
    }
}

/// Nice linear ticks between lo and hi: at most `major_count` of them, 1, 2 or 5 times a
/// power of ten apart, or four or five times as dense when `with_minor`; the two ends if no
/// such step fits.
fn linear_ticks(lo: f64, hi: f64, major_count: usize, with_minor: bool) -> Vec<f64> {
    let half_span = 0.5 * hi - 0.5 * lo; // overflow-free
    if !(half_span.is_finite() && half_span > 0.0) {
        return vec![lo, hi];
    }
    // A step of at least span / (count - 1) gives at most `count` ticks.
    let major = nice_step(2.0 * (half_span / (major_count.max(2) - 1) as f64));
    let step = if with_minor {
        let mantissa = major / 10f64.powf(major.log10().floor());
        major
            / if (mantissa - 2.0).abs() < 1e-9 {
                4.0
            } else {
                5.0
            }
    } else {
        major
    };
    let (first, last) = ((lo / step).ceil(), (hi / step).floor());
    // Ticks are k * step for whole k; when k is too large to be exact, or there would be too
    // many, fall back to the ends.
    if !(first.is_finite() && last.is_finite())
        || first.abs() > 1e15
        || last.abs() > 1e15
        || last < first
        || last - first > MAX_TICKS as f64
    {
        return vec![lo, hi];
    }
    let ticks: Vec<f64> = (first as i64..=last as i64)
        .map(|k| k as f64 * step)
        .filter(|v| v.is_finite())
        .collect();
    if ticks.is_empty() {
        vec![lo, hi]
    } else {
        ticks
    }
}

/// The smallest of 1, 2, 5 times a power of ten that is at least `raw`.
fn nice_step(raw: f64) -> f64 {
    if !(raw.is_finite() && raw > 0.0) {
        return 1.0;
    }
    let exponent = raw.log10().floor();
    let base = 10f64.powf(exponent);
    let mantissa = raw / base;
    let nice = if mantissa <= 1.0 {
        1.0
    } else if mantissa <= 2.0 {
        2.0
    } else if mantissa <= 5.0 {
        5.0
    } else {
        10.0
    };
    let step = nice * base;
    if step.is_finite() && step > 0.0 {
        step
    } else {
        raw
    }
}

/// Log ticks between 10^llo and 10^lhi: powers of ten (every k-th decade when there are more
/// than `major_count`), with 2..9 times each decade added as minor ticks when asked and at
/// most `max_count` in all; inside a range narrower than two decades, 1-2-5 (or 1..9)
/// multiples instead.
fn log_ticks(
    llo: f64,
    lhi: f64,
    major_count: usize,
    max_count: usize,
    with_minor: bool,
) -> Vec<f64> {
    let (first, last) = (llo.ceil(), lhi.floor());
    let decades = if last >= first {
        (last - first) as usize + 1
    } else {
        0
    };
    let in_range = |v: f64| v.is_finite() && v > 0.0 && (llo..=lhi).contains(&v.log10());
    if decades >= 2 {
        let every = (decades as f64 / major_count as f64).ceil().max(1.0) as i64;
        let mut ticks: Vec<f64> = (first as i64..=last as i64)
            .filter(|k| k.rem_euclid(every) == 0)
            .map(|k| 10f64.powi(k as i32))
            .filter(|v| in_range(*v))
            .collect();
        if with_minor && every == 1 && decades * 9 <= max_count {
            let lowest = first as i64 - 1;
            for k in lowest..=last as i64 {
                for m in 2..=9 {
                    let v = f64::from(m) * 10f64.powi(k as i32);
                    if in_range(v) {
                        ticks.push(v);
                    }
                }
            }
        }
        return ticks;
    }
    // Less than two decades: multiples of powers of ten inside the range.
    let lowest = llo.floor() as i64;
    let highest = lhi.floor() as i64;
    let multiples = |ms: &[u32]| -> Vec<f64> {
        (lowest..=highest)
            .flat_map(|k| ms.iter().map(move |m| f64::from(*m) * 10f64.powi(k as i32)))
            .filter(|v| in_range(*v))
            .collect()
    };
    let all = multiples(&[1, 2, 3, 4, 5, 6, 7, 8, 9]);
    let coarse = multiples(&[1, 2, 5]);
    if with_minor && all.len() >= 2 && all.len() <= max_count {
        return all;
    }
    if coarse.len() >= 2 && coarse.len() <= major_count {
        return coarse;
    }
    if all.len() >= 2 && all.len() <= major_count {
        return all;
    }
    // Narrower still: linear ticks inside the range.
    linear_ticks(10f64.powf(llo), 10f64.powf(lhi), major_count, with_minor)
}

/// Label of a tick on a linear axis spanning lo..hi: as many decimals as the tick spacing
/// needs, plain or in scientific form for very large or small magnitudes.
fn format_linear_tick(value: f64, lo: f64, hi: f64) -> String {
    let magnitude = lo.abs().max(hi.abs());
    let span = 0.5 * hi - 0.5 * lo;
    // Digits needed to tell ticks apart: from the largest magnitude down to a tenth of the
    // span's order.
    let span_exp = (2.0 * span).log10().floor();
    let mag_exp = magnitude.log10().floor();
    let digits = if span_exp.is_finite() && mag_exp.is_finite() {
        (mag_exp - span_exp + 2.0).clamp(1.0, 15.0) as usize
    } else {
        4
    };
    format_number(value, digits)
}

/// Label of a tick on a log axis: plain for 0.001 ..= 10000, else `m×10ⁿ` (or `10ⁿ`).
fn format_log_tick(value: f64) -> String {
    let exponent = value.log10().floor();
    if (-3.0..=4.0).contains(&exponent) {
        return format_number(value, 3);
    }
    let mantissa = value / 10f64.powf(exponent);
    let rounded = (mantissa * 100.0).round() / 100.0;
    let power = format!("10{}", superscript(exponent as i64));
    if (rounded - 1.0).abs() < 1e-9 {
        power
    } else {
        format!("{}×{power}", trim_decimal(&format!("{rounded:.2}")))
    }
}

/// A number with `digits` significant digits, trailing zeros removed; plain for magnitudes
/// 1e-4 ..= 1e6, else scientific (`1.5e-7`). Never prints a negative zero.
pub(crate) fn format_number(value: f64, digits: usize) -> String {
    if !value.is_finite() {
        return value.to_string();
    }
    let digits = digits.clamp(1, 17);
    if value == 0.0 {
        return "0".to_string();
    }
    let exponent = value.abs().log10().floor();
    let text = if (-4.0..6.0).contains(&exponent) {
        let decimals = (digits as f64 - 1.0 - exponent).max(0.0) as usize;
        trim_decimal(&format!("{value:.decimals$}"))
    } else {
        let formatted = format!("{value:.prec$e}", prec = digits - 1);
        match formatted.split_once('e') {
            Some((mantissa, exp)) => format!("{}e{exp}", trim_decimal(mantissa)),
            None => formatted,
        }
    };
    if text == "-0" { "0".to_string() } else { text }
}

/// Removes trailing zeros (and a trailing point) from a decimal number.
fn trim_decimal(text: &str) -> String {
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text.to_string()
    }
}

/// An integer in superscript digits, e.g. -12 as `⁻¹²`.
fn superscript(n: i64) -> String {
    const DIGITS: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let mut out = String::new();
    if n < 0 {
        out.push('⁻');
    }
    for c in n.unsigned_abs().to_string().chars() {
        let digit = c.to_digit(10).unwrap_or(0) as usize;
        out.push(DIGITS.get(digit).copied().unwrap_or('?'));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_range_pads_and_skips_undrawable_values() {
        let (lo, hi) =
            fit_range([1.0, f64::NAN, 3.0, f64::INFINITY], Scale::Linear, 0.05).expect("range");
        assert!(
            (lo - 0.9).abs() < 1e-12 && (hi - 3.1).abs() < 1e-12,
            "{lo} {hi}"
        );
        // Zero and negative values are not drawable on a log axis.
        let (lo, hi) = fit_range([0.0, -1.0, 10.0, 1000.0], Scale::Log, 0.0).expect("range");
        assert!(
            (lo - 10.0).abs() < 1e-9 && (hi - 1000.0).abs() < 1e-9,
            "{lo} {hi}"
        );
        assert!(fit_range([f64::NAN, 0.0], Scale::Log, 0.0).is_none());
        assert!(fit_range([], Scale::Linear, 0.0).is_none());
    }

    #[test]
    fn degenerate_ranges_open_up() {
        assert_eq!(
            fit_range([0.0, 0.0], Scale::Linear, 0.05),
            Some((-1.0, 1.0))
        );
        assert_eq!(fit_range([-5.0], Scale::Linear, 0.05), Some((-5.5, -4.5)));
        let (lo, hi) = fit_range([100.0], Scale::Log, 0.05).expect("range");
        assert!((lo.log10() - 1.5).abs() < 1e-12 && (hi.log10() - 2.5).abs() < 1e-12);
        // Extremes stay finite and ordered.
        let (lo, hi) = fit_range([-f64::MAX, f64::MAX], Scale::Linear, 0.05).expect("range");
        assert!(lo.is_finite() && hi.is_finite() && lo < hi);
        let (lo, hi) = fit_range([f64::MIN_POSITIVE, f64::MAX], Scale::Log, 0.05).expect("range");
        assert!(lo > 0.0 && hi.is_finite() && lo < hi);
    }

    #[test]
    fn linear_ticks_are_nice_multiples() {
        // Six ticks allowed on 0..1: a step of 1/5 = 0.2 exactly fits.
        let ticks = linear_ticks(0.0, 1.0, 6, false);
        assert_eq!(ticks.len(), 6);
        assert!(
            ticks
                .iter()
                .zip([0.0, 0.2, 0.4, 0.6, 0.8, 1.0])
                .all(|(a, b)| (a - b).abs() < 1e-12)
        );
        // 360 degrees with at most 10 ticks: 40 rounds up to 50.
        let phase = linear_ticks(-180.0, 180.0, 10, false);
        assert_eq!(
            phase,
            (-3..=3).map(|k| f64::from(k) * 50.0).collect::<Vec<_>>()
        );
        // Minor ticks split a step of 50 in five (10 apart).
        assert_eq!(linear_ticks(-180.0, 180.0, 10, true).len(), 37);
        // A tiny span around a huge value cannot be ticked exactly: the ends.
        assert_eq!(
            linear_ticks(1e17, 1e17 + 64.0, 5, false),
            vec![1e17, 1e17 + 64.0]
        );
    }

    #[test]
    fn log_ticks_are_decades_with_minor_multiples() {
        let ticks = log_ticks(-1.0, 2.0, 10, 10, false);
        assert_eq!(ticks, vec![0.1, 1.0, 10.0, 100.0]);
        let with_minor = log_ticks(-1.0, 2.0, 10, 100, true);
        assert!(with_minor.contains(&0.2) && with_minor.contains(&90.0));
        assert!(!with_minor.iter().any(|v| *v > 100.0 || *v < 0.1));
        // 600 decades, at most 10 ticks: every 61st decade.
        let wide = log_ticks(-300.0, 300.0, 10, 100, false);
        assert!(wide.len() <= 11 && wide.len() >= 5, "{wide:?}");
        // Within one decade: 1-2-5 multiples, or all multiples.
        assert_eq!(
            log_ticks(2f64.log10(), 8f64.log10(), 10, 10, false),
            vec![2.0, 5.0]
        );
    }

    #[test]
    fn labels_read_well() {
        assert_eq!(format_number(-0.0, 3), "0");
        assert_eq!(format_number(0.30000000000000004, 3), "0.3");
        assert_eq!(format_number(1234.56, 3), "1235");
        assert_eq!(format_number(1.5e-7, 3), "1.5e-7");
        assert_eq!(format_log_tick(1e-5), "10⁻⁵");
        assert_eq!(format_log_tick(2e-5), "2×10⁻⁵");
        assert_eq!(format_log_tick(0.01), "0.01");
        assert_eq!(format_log_tick(1000.0), "1000");
        assert_eq!(format_linear_tick(-0.5, -1.0, 1.0), "-0.5");
        assert_eq!(format_linear_tick(90.0, -180.0, 180.0), "90");
        assert_eq!(axis_label("|x3/x00|", "m/m"), "|x3/x00| (m/m)");
        assert_eq!(axis_label("max relative error", ""), "max relative error");
    }

    #[test]
    fn mapping_is_monotonic_and_bounded() {
        let axis = AxisCoord::fit([1e-3, 1e3], Scale::Log, 0.0).expect("axis");
        assert_eq!(axis.map(&1e-3, (0, 600)), 0);
        assert_eq!(axis.map(&1.0, (0, 600)), 300);
        assert_eq!(axis.map(&1e3, (0, 600)), 600);
        // Undrawable values land far outside, but within the overshoot bound.
        let below = axis.map(&0.0, (0, 600));
        assert!(below < 0 && f64::from(below) >= -MAX_PIXEL_OVERSHOOT);
        let linear = AxisCoord::linear(-1.0, 1.0).expect("axis");
        assert_eq!(linear.map(&0.0, (100, 0)), 50);
    }
}
