//! Empty, degenerate and invalid input: errors that name what is wrong, or valid figures,
//! never a panic.

use crate::common::*;
use pendkit_plot::{
    Amplitude, Axis, BodeSeries, BodyOutline, Contribution, Figure, LinePlot, ModeChart,
    ModeMarker, ModeShapePlot, Orientation, PlotError, Scale, Series, Solid, TradeoffChart,
    TradeoffPoint,
};

fn line_plot(series: Vec<Series>, y_scale: Scale) -> LinePlot {
    let mut plot = LinePlot::new(
        "",
        Axis::new("p", "m", Scale::Linear),
        Axis::new("v", "Hz", y_scale),
    );
    plot.series = series;
    plot
}

fn nothing(error: PlotError) -> String {
    match error {
        PlotError::NothingToPlot { reason, .. } => reason,
        other => panic!("expected NothingToPlot, got {other}"),
    }
}

#[test]
fn empty_figures_are_errors() {
    assert_eq!(
        nothing(line_plot(vec![], Scale::Linear).to_svg().unwrap_err()),
        "no series"
    );
    let mut bode = bode();
    bode.series.clear();
    assert_eq!(nothing(bode.to_svg().unwrap_err()), "no series");
    let mut budget = noise();
    budget.frequency_hz.clear();
    budget.total.asd.clear();
    budget.contributions.clear();
    assert_eq!(nothing(budget.to_svg().unwrap_err()), "no frequencies");
    assert_eq!(
        nothing(ModeChart::new("", vec![]).to_svg().unwrap_err()),
        "no modes"
    );
    assert_eq!(
        nothing(ModeShapePlot::new("").to_svg().unwrap_err()),
        "no bodies and no wires"
    );
    assert_eq!(
        nothing(TradeoffChart::new("", vec![]).to_png().unwrap_err()),
        "no variants"
    );
}

#[test]
fn all_nan_data_is_nothing_to_plot_but_one_good_series_is_enough() {
    let nan = Series::new("nan", vec![1.0, 2.0], vec![f64::NAN, f64::NAN]);
    let reason = nothing(
        line_plot(vec![nan.clone()], Scale::Linear)
            .to_svg()
            .unwrap_err(),
    );
    assert!(reason.contains("finite"), "{reason}");
    // Zeros and negatives cannot go on a log axis.
    let zeros = Series::new("zeros", vec![1.0, 2.0], vec![0.0, -1.0]);
    let reason = nothing(line_plot(vec![zeros], Scale::Log).to_svg().unwrap_err());
    assert!(reason.contains("positive"), "{reason}");
    // With a good series beside it, the empty one stays in the legend, marked.
    let good = Series::new("good", vec![1.0, 2.0], vec![3.0, 4.0]);
    let svg = line_plot(vec![nan, good], Scale::Linear)
        .to_svg()
        .expect("svg");
    let doc = parse(&svg);
    let all = texts(&doc);
    assert!(all.iter().any(|t| t == "nan (nothing to draw)"), "{all:?}");
}

#[test]
fn single_points_and_zero_ranges_draw() {
    // One point: drawn as a dot, axes opened around it.
    let single = line_plot(vec![Series::new("one", vec![5.0], vec![7.0])], Scale::Log);
    let svg = single.to_svg().expect("svg");
    assert!(parse(&svg).descendants().any(|n| n.has_tag_name("circle")));
    // Constant values (zero range) on linear and log axes.
    for scale in [Scale::Linear, Scale::Log] {
        let flat = line_plot(
            vec![Series::new("flat", vec![1.0, 2.0, 3.0], vec![2.0; 3])],
            scale,
        );
        parse(&flat.to_svg().expect("svg"));
        let zero = line_plot(vec![Series::new("zero", vec![0.0; 3], vec![1.0; 3])], scale);
        parse(&zero.to_svg().expect("svg"));
    }
    single.to_png().expect("png");
}

#[test]
fn zero_and_nan_magnitudes_are_skipped_in_bode_plots() {
    let f = vec![0.1, 1.0, 10.0, 100.0, -1.0, 0.0];
    let response = vec![
        (1.0, 0.0),
        (0.0, 0.0),
        (f64::NAN, 1.0),
        (0.5, -0.5),
        (1.0, 1.0),
        (1.0, 1.0),
    ];
    let mut plot = pendkit_plot::BodePlot::new("", "|H|", "");
    plot.series.push(BodeSeries::new("holes", f, response));
    parse(&plot.to_svg().expect("svg"));
    plot.to_png().expect("png");
    // Nothing drawable at all is an error.
    plot.series[0].response = vec![(0.0, 0.0); 6];
    let reason = nothing(plot.to_svg().unwrap_err());
    assert!(reason.contains("frequency and magnitude"), "{reason}");
}

#[test]
fn mismatched_lengths_name_the_series() {
    let plot = line_plot(
        vec![Series::new("short", vec![1.0, 2.0], vec![1.0])],
        Scale::Linear,
    );
    let message = plot.to_svg().unwrap_err().to_string();
    assert_eq!(
        message,
        "line plot: y of series `short` has 1 values but 2 were expected"
    );
    let mut budget = noise();
    budget
        .contributions
        .push(Contribution::new("odd", vec![1.0]));
    let message = budget.to_svg().unwrap_err().to_string();
    assert!(
        message.contains("ASD of `odd`") && message.contains("100 were expected"),
        "{message}"
    );
    let mut bode = bode();
    bode.series[1].response.pop();
    assert!(matches!(
        bode.to_svg(),
        Err(PlotError::LengthMismatch { .. })
    ));
}

#[test]
fn trade_off_values_are_checked_per_variant() {
    let chart = |s: f64, e: f64| TradeoffChart::new("", vec![TradeoffPoint::new("v1", s, e)]);
    let message = chart(f64::NAN, 0.1).to_svg().unwrap_err().to_string();
    assert_eq!(
        message,
        "trade-off chart: seconds of variant `v1` is NaN, not a finite number"
    );
    let message = chart(0.0, 0.1).to_svg().unwrap_err().to_string();
    assert!(
        message.contains("seconds of variant `v1`") && message.contains("> 0"),
        "{message}"
    );
    let message = chart(1.0, -0.1).to_svg().unwrap_err().to_string();
    assert!(
        message.contains("max relative error of variant `v1`"),
        "{message}"
    );
    let mut bad_tolerance = chart(1.0, 0.1);
    bad_tolerance.tolerance = Some(0.0);
    assert!(matches!(
        bad_tolerance.to_svg(),
        Err(PlotError::InvalidInput { .. })
    ));
    // Only the reference (zero error): a valid figure.
    parse(&chart(1.0, 0.0).to_svg().expect("svg"));
}

#[test]
fn mode_values_are_checked_per_mode() {
    let chart = |f: f64, unstable: bool| {
        ModeChart::new(
            "",
            vec![ModeMarker {
                frequency_hz: f,
                family: "L".into(),
                label: None,
                unstable,
            }],
        )
    };
    let message = chart(f64::INFINITY, false)
        .to_svg()
        .unwrap_err()
        .to_string();
    assert_eq!(
        message,
        "mode chart: frequency of mode 0 (L) is inf, not a finite number"
    );
    assert!(matches!(
        chart(-1.0, false).to_svg(),
        Err(PlotError::InvalidInput { .. })
    ));
    parse(
        &chart(-1.0, true)
            .to_svg()
            .expect("unstable at its growth rate"),
    );
    assert!(matches!(
        chart(0.0, false).to_svg(),
        Err(PlotError::NothingToPlot { .. })
    ));
    // Zero-frequency modes beside others are counted under the title.
    let mut modes = chart(1.0, false);
    modes.modes.push(ModeMarker::new(0.0, "Y"));
    let doc_svg = modes.to_svg().expect("svg");
    let all = texts(&parse(&doc_svg));
    assert!(
        all.iter()
            .any(|t| t == "1 mode at 0 Hz not shown (log axis)"),
        "{all:?}"
    );
}

#[test]
fn mode_shape_geometry_is_checked_per_body() {
    let mut plot = mode_shape();
    plot.bodies[0].centre[2] = f64::NAN;
    let message = plot.to_svg().unwrap_err().to_string();
    assert_eq!(
        message,
        "mode shape: centre of body `mass` is NaN, not a finite number"
    );
    let mut plot = mode_shape();
    plot.bodies[0].orientation =
        Orientation::Matrix([[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 1.0]]);
    assert!(
        plot.to_svg()
            .unwrap_err()
            .to_string()
            .contains("not a rotation")
    );
    let mut plot = mode_shape();
    plot.bodies[0].solid = Solid::Cylinder {
        radius: -1.0,
        half_length: 0.1,
        axis: pendkit_plot::BodyAxis::X,
    };
    assert!(plot.to_svg().unwrap_err().to_string().contains("negative"));
    let mut plot = mode_shape();
    plot.amplitude = Amplitude::Auto { fraction: 0.0 };
    assert!(matches!(plot.to_svg(), Err(PlotError::InvalidInput { .. })));
    let mut plot = mode_shape();
    plot.wires[0].bottom_displacement[1] = f64::INFINITY;
    assert!(plot.to_svg().unwrap_err().to_string().contains("wire 0"));
    // A point body, no wires, no displacement: a valid figure that says so.
    let mut point = ModeShapePlot::new("");
    point.bodies.push(BodyOutline::new(
        "dot",
        [0.0; 3],
        Solid::Box {
            half_sizes: [0.0; 3],
        },
    ));
    let svg = point.to_svg().expect("svg");
    let all = texts(&parse(&svg));
    assert!(
        all.iter().any(|t| t.starts_with("no displacement")),
        "{all:?}"
    );
    point.to_png().expect("png");
}

#[test]
fn figure_sizes_are_checked() {
    for size in [(0, 600), (63, 600), (960, 9000), (8192, 8192)] {
        let mut plot = sweep();
        plot.size = size;
        let error = plot.to_png().unwrap_err();
        assert!(
            matches!(error, PlotError::InvalidSize { .. }),
            "{size:?}: {error}"
        );
    }
    let mut small = sweep();
    small.size = (64, 64);
    parse(&small.to_svg().expect("smallest size"));
    small.to_png().expect("smallest size");
}
