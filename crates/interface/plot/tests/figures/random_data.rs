//! Random data, including NaN, infinities, zeros, negatives and extreme magnitudes: every
//! figure either renders (SVG that parses as XML) or reports that there is nothing to plot,
//! and never panics.

use proptest::prelude::*;

use crate::common::parse;
use pendkit_plot::{
    Axis, BodePlot, BodeSeries, Contribution, Figure, LinePlot, ModeChart, ModeMarker, NoiseBudget,
    PlotError, Scale, Series, TradeoffChart, TradeoffPoint,
};

fn value() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => -1e3..1e3f64,
        2 => 1e-12..1e12f64,
        1 => Just(0.0),
        1 => Just(-0.0),
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
        1 => Just(f64::MAX),
        1 => Just(-f64::MAX),
        1 => Just(f64::MIN_POSITIVE),
        1 => Just(5e-324),
        1 => Just(1e300),
    ]
}

fn scale() -> impl Strategy<Value = Scale> {
    prop_oneof![Just(Scale::Linear), Just(Scale::Log)]
}

fn series() -> impl Strategy<Value = Series> {
    (0usize..12).prop_flat_map(|n| {
        (
            prop::collection::vec(value(), n),
            prop::collection::vec(value(), n),
        )
            .prop_map(|(x, y)| Series::new("s", x, y))
    })
}

/// Rendered, or refused because nothing can be drawn; anything else fails the test.
fn renders_or_has_nothing(result: Result<String, PlotError>) -> Result<(), TestCaseError> {
    match result {
        Ok(svg) => {
            parse(&svg);
            Ok(())
        }
        Err(PlotError::NothingToPlot { .. }) => Ok(()),
        Err(other) => Err(TestCaseError::fail(format!("unexpected error: {other}"))),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn line_plots_of_random_series(series in prop::collection::vec(series(), 0..4), x in scale(), y in scale()) {
        let mut plot = LinePlot::new("random", Axis::new("x", "m", x), Axis::new("y", "m", y));
        plot.series = series;
        plot.markers = true;
        renders_or_has_nothing(plot.to_svg())?;
    }

    #[test]
    fn bode_plots_of_random_responses(
        data in prop::collection::vec((value(), value(), value()), 0..30),
        unwrapped in any::<bool>(),
    ) {
        let mut plot = BodePlot::new("random", "|H|", "m/N");
        plot.series.push(BodeSeries::new(
            "h",
            data.iter().map(|d| d.0).collect(),
            data.iter().map(|d| (d.1, d.2)).collect(),
        ));
        if unwrapped {
            plot.phase = pendkit_plot::PhaseDisplay::Unwrapped;
        }
        renders_or_has_nothing(plot.to_svg())?;
    }

    #[test]
    fn noise_budgets_of_random_curves(data in prop::collection::vec((value(), value(), value()), 1..30)) {
        let mut budget = NoiseBudget::new(
            "random",
            "ASD",
            "m/√Hz",
            data.iter().map(|d| d.0).collect(),
            Contribution::new("total", data.iter().map(|d| d.1).collect()),
        );
        budget.contributions.push(Contribution::new("part", data.iter().map(|d| d.2).collect()));
        renders_or_has_nothing(budget.to_svg())?;
    }

    #[test]
    fn mode_charts_of_random_finite_frequencies(
        modes in prop::collection::vec((-1e6..1e6f64, 0usize..5, any::<bool>()), 1..40)
    ) {
        let families = ["L", "P", "violin", "custom", "Y"];
        let chart = ModeChart::new("random", modes.iter().map(|&(f, family, unstable)| ModeMarker {
            frequency_hz: if unstable { f } else { f.abs() },
            family: families[family].to_string(),
            label: None,
            unstable,
        }).collect());
        renders_or_has_nothing(chart.to_svg())?;
    }

    #[test]
    fn trade_off_charts_of_random_variants(
        points in prop::collection::vec((1e-9..1e6f64, prop_oneof![Just(0.0), 1e-300..1e300f64]), 1..20)
    ) {
        let chart = TradeoffChart::new("random", points.iter().enumerate()
            .map(|(i, &(s, e))| TradeoffPoint::new(format!("v{i}"), s, e)).collect());
        renders_or_has_nothing(chart.to_svg())?;
    }
}

proptest! {
    // PNG rendering draws every pixel: fewer cases.
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    #[test]
    fn png_of_random_series(series in prop::collection::vec(series(), 1..3), x in scale(), y in scale()) {
        let mut plot = LinePlot::new("random", Axis::new("x", "", x), Axis::new("y", "", y));
        plot.series = series;
        match plot.to_png() {
            Ok(bytes) => prop_assert!(bytes.starts_with(b"\x89PNG")),
            Err(PlotError::NothingToPlot { .. }) => {}
            Err(other) => return Err(TestCaseError::fail(format!("unexpected error: {other}"))),
        }
    }
}
