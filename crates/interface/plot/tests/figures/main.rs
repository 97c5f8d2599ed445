//! Integration tests of pendkit-plot: every figure rendered to SVG (read back as XML and
//! checked for its labels, legend and geometry) and to PNG (decoded and checked for size and
//! content); bad and degenerate input; random data.

mod bad_input;
mod common;
mod random_data;

use common::*;
use pendkit_plot::{Figure, PhaseDisplay, PlotError};

/// The colours the crate gives the first two series (the "tab10" palette).
const FIRST: &str = "#1F77B4";
const SECOND: &str = "#FF7F0E";

fn assert_has(texts: &[String], wanted: &[&str]) {
    for w in wanted {
        assert!(
            texts.iter().any(|t| t == w),
            "no text `{w}` among {texts:?}"
        );
    }
}

#[test]
fn bode_svg_has_axis_titles_legend_and_both_panels() {
    let svg = bode().to_svg().expect("svg");
    assert!(svg.starts_with("<svg"), "inline-embeddable: no XML prolog");
    let doc = parse(&svg);
    let root = doc.root_element();
    assert_eq!(root.attribute("width"), Some("960"));
    assert_eq!(root.attribute("height"), Some("720"));
    assert_has(
        &texts(&doc),
        &[
            "Pendulum",
            "|x3/x00| (m/m)",
            "phase (deg)",
            "frequency (Hz)",
            "x3/x00",
            "half",
        ],
    );
    // Each series: one magnitude line, and phase lines (plus the legend sample).
    for colour in [FIRST, SECOND] {
        let lines = shapes_with(&doc, "polyline", "stroke", colour);
        let long = lines.iter().filter(|l| l.len() > 50).count();
        assert!(long >= 2, "{colour}: {} long lines", long);
    }
    // No external references of any kind.
    assert!(!svg.contains("href") && !svg.contains("url("));
}

#[test]
fn wrapped_phase_breaks_where_it_wraps_and_unwrapped_does_not() {
    // A pure delay of 0.5 s: phase = -360 f τ = -180 f degrees, unit magnitude. Wrapped into
    // (-180, 180] it jumps at f = 1, 3, 5, 7, 9 Hz: five breaks between 0.1 and 10 Hz, so six
    // phase lines; unwrapped, one. Plus one magnitude line either way.
    let f = logspace(0.1, 10.0, 400);
    let delay: Vec<(f64, f64)> = f
        .iter()
        .map(|&f| {
            let angle = -2.0 * std::f64::consts::PI * f * 0.5;
            (angle.cos(), angle.sin())
        })
        .collect();
    let mut plot = pendkit_plot::BodePlot::new("", "|H|", "");
    plot.series
        .push(pendkit_plot::BodeSeries::new("delay", f, delay));
    let count = |plot: &pendkit_plot::BodePlot| {
        let svg = plot.to_svg().expect("svg");
        let doc = parse(&svg);
        // Drop the legend sample (two points).
        shapes_with(&doc, "polyline", "stroke", FIRST)
            .iter()
            .filter(|l| l.len() > 2)
            .count()
    };
    assert_eq!(count(&plot), 1 + 6);
    plot.phase = PhaseDisplay::Unwrapped;
    assert_eq!(count(&plot), 1 + 1);
}

#[test]
fn log_axes_map_a_power_law_to_a_straight_line_of_its_slope() {
    // y = x² on log-log axes from x = 1 to 100: in pixels, a straight line whose slope is
    // 2 (pixels per decade of y) / (pixels per decade of x), with the pixels per decade read
    // off the tick labels' positions (x labels centred below, y labels right-aligned).
    let x = logspace(1.0, 100.0, 50);
    let mut plot = pendkit_plot::LinePlot::new(
        "",
        pendkit_plot::Axis::new("x", "", pendkit_plot::Scale::Log),
        pendkit_plot::Axis::new("y", "", pendkit_plot::Scale::Log),
    );
    plot.series.push(pendkit_plot::Series::new(
        "square",
        x.clone(),
        x.iter().map(|v| v * v).collect(),
    ));
    let svg = plot.to_svg().expect("svg");
    let doc = parse(&svg);
    let labels = placed_texts(&doc);
    let at = |text: &str, anchor: &str, coordinate: fn(&(String, f64, f64, String)) -> f64| {
        labels
            .iter()
            .find(|l| l.0 == text && l.3 == anchor)
            .map(coordinate)
            .unwrap_or_else(|| panic!("no tick label {text} ({anchor})"))
    };
    let x_decade = at("10", "middle", |l| l.1) - at("1", "middle", |l| l.1);
    let y_decade = at("1", "end", |l| l.2) - at("10", "end", |l| l.2);
    assert!(x_decade > 100.0 && y_decade > 20.0, "{x_decade} {y_decade}");
    let line = shapes_with(&doc, "polyline", "stroke", FIRST)
        .into_iter()
        .max_by_key(|l| l.len())
        .expect("series line");
    assert_eq!(line.len(), 50);
    let (first, last) = (line[0], line[49]);
    let slope = (first.1 - last.1) / (last.0 - first.0);
    let expected = 2.0 * y_decade / x_decade;
    // Pixel positions are rounded to whole pixels over ~700 px: 0.5 % is a few pixels.
    assert!(
        (slope / expected - 1.0).abs() < 5e-3,
        "slope {slope}, expected {expected}"
    );
    for p in &line {
        // Every point on the straight line through the ends, within rounding.
        let on_line = first.1 - slope * (p.0 - first.0);
        assert!(
            (p.1 - on_line).abs() <= 1.5,
            "{p:?} off the line by {}",
            p.1 - on_line
        );
    }
}

#[test]
fn noise_budget_draws_the_total_thicker_than_its_contributions() {
    let svg = noise().to_svg().expect("svg");
    let doc = parse(&svg);
    assert_has(
        &texts(&doc),
        &[
            "Budget",
            "displacement ASD (m/√Hz)",
            "frequency (Hz)",
            "total",
            "fibre_bending",
            "blade_n",
        ],
    );
    let width_of = |colour: &str| -> Vec<f64> {
        doc.descendants()
            .filter(|n| n.has_tag_name("polyline") && n.attribute("stroke") == Some(colour))
            .filter(|n| points(n.attribute("points").unwrap_or("")).len() > 2)
            .filter_map(|n| n.attribute("stroke-width")?.parse().ok())
            .collect()
    };
    let total = width_of("#000000").into_iter().fold(0.0, f64::max);
    let parts: Vec<f64> = [FIRST, SECOND].iter().flat_map(|c| width_of(c)).collect();
    assert_eq!(parts.len(), 2, "one line per contribution");
    assert!(
        parts.iter().all(|w| *w < total),
        "total {total}, contributions {parts:?}"
    );
}

#[test]
fn mode_chart_has_rows_markers_and_the_unstable_mode() {
    let svg = modes().to_svg().expect("svg");
    let doc = parse(&svg);
    assert_has(
        &texts(&doc),
        &["L", "P", "V", "Y", "violin", "frequency (Hz)", "unstable Y"],
    );
    // Six stable modes and one legend sample are filled circles.
    let circles = doc
        .descendants()
        .filter(|n| n.has_tag_name("circle"))
        .count();
    assert_eq!(circles, 6 + 1);
    // The unstable mode is a red cross: two strokes, on the marker and in the legend.
    let red = shapes_with(&doc, "polyline", "stroke", "#D62728");
    assert_eq!(red.len(), 4);
}

#[test]
fn mode_shape_keeps_shapes_undistorted_and_states_the_magnification() {
    let svg = mode_shape().to_svg().expect("svg");
    let doc = parse(&svg);
    let all = texts(&doc);
    assert_has(
        &all,
        &[
            "side view (x–z)",
            "front view (y–z)",
            "x (m)",
            "y (m)",
            "z (m)",
            "mass",
        ],
    );
    // The drawing spans 1.1 m (z from -0.1 to 1.0); the largest displacement is 1 mm:
    // magnified to 10 % of 1.1 m, that is ×110.
    assert!(all.iter().any(|t| t.contains("magnified ×110,")), "{all:?}");
    // The box at rest (light grey fill): 0.6 x 0.2 m from the side, 0.4 x 0.2 m from the
    // front. Equal scales make its pixel aspect ratios 3 and 2, to within rounding.
    let rest = shapes_with(&doc, "polygon", "fill", "#E4E4E4");
    assert_eq!(rest.len(), 2);
    let aspect = |p: &Vec<(f64, f64)>| {
        let (xs, ys): (Vec<f64>, Vec<f64>) = p.iter().copied().unzip();
        let span = |v: &[f64]| {
            v.iter().fold(f64::NEG_INFINITY, |a, b| a.max(*b))
                - v.iter().fold(f64::INFINITY, |a, b| a.min(*b))
        };
        (span(&xs), span(&ys))
    };
    let (side_w, side_h) = aspect(&rest[0]);
    let (front_w, front_h) = aspect(&rest[1]);
    assert!(
        (side_w / side_h - 3.0).abs() < 3.0 * 2.0 / side_h,
        "side {side_w} x {side_h}"
    );
    assert!(
        (front_w / front_h - 2.0).abs() < 2.0 * 2.0 / front_h,
        "front {front_w} x {front_h}"
    );
    // Same scale in both views: the same 0.2 m height in pixels.
    assert!((side_h - front_h).abs() <= 1.0, "{side_h} {front_h}");
}

#[test]
fn tradeoff_marks_the_front_and_puts_zero_error_on_the_bottom_edge() {
    let svg = tradeoff().to_svg().expect("svg");
    let doc = parse(&svg);
    let all = texts(&doc);
    assert_has(
        &all,
        &[
            "time (s)",
            "max relative error",
            "fast",
            "middle",
            "slow, worse",
            "reference",
        ],
    );
    assert!(
        all.iter().any(|t| t.contains("bottom edge")),
        "legend says where zero error is"
    );
    assert!(all.iter().any(|t| t.contains("Pareto front")));
    // The front (fast, middle, reference) is one red line through three points.
    let front = shapes_with(&doc, "polyline", "stroke", "#D62728");
    assert!(front.iter().any(|l| l.len() == 3), "{front:?}");
    // The zero-error marker (an open black square) is centred on the x axis line, whose y
    // is the bottom end of the y axis line.
    let y_axis = doc
        .descendants()
        .filter(|n| n.has_tag_name("polyline") && n.attribute("stroke") == Some("#000000"))
        .map(|n| points(n.attribute("points").unwrap_or("")))
        .find(|p| p.len() == 2 && p[0].0 == p[1].0 && (p[1].1 - p[0].1).abs() > 100.0)
        .expect("y axis line");
    let bottom = y_axis[0].1.max(y_axis[1].1);
    let square = doc
        .descendants()
        .find(|n| {
            n.has_tag_name("rect")
                && n.attribute("fill") == Some("none")
                && n.attribute("stroke") == Some("#000000")
        })
        .expect("zero-error marker");
    let number = |k: &str| {
        square
            .attribute(k)
            .and_then(|v| v.parse::<f64>().ok())
            .expect(k)
    };
    let centre = number("y") + number("height") / 2.0;
    assert!(
        (centre - bottom).abs() <= 1.0,
        "marker at {centre}, bottom edge at {bottom}"
    );
}

#[test]
fn line_plot_labels_both_axes_with_units() {
    let svg = sweep().to_svg().expect("svg");
    let doc = parse(&svg);
    assert_has(
        &texts(&doc),
        &[
            "Sweep",
            "fibre radius (mm)",
            "frequency (Hz)",
            "violin",
            "bounce",
        ],
    );
}

/// Every figure as PNG: the size asked for, and a picture (many colours, neither blank nor
/// filled), with text drawn from the bundled font (dark pixels in the title band).
#[test]
fn png_output_is_a_valid_picture_for_every_figure() {
    /// A figure's name, PNG rendering and requested size.
    type Rendered = (&'static str, Result<Vec<u8>, PlotError>, (u32, u32));
    fn rendered(name: &'static str, figure: &impl Figure) -> Rendered {
        (name, figure.to_png(), figure.size())
    }
    let pngs = [
        rendered("bode", &bode()),
        rendered("noise", &noise()),
        rendered("modes", &modes()),
        rendered("mode shape", &mode_shape()),
        rendered("tradeoff", &tradeoff()),
        rendered("sweep", &sweep()),
    ];
    for (name, png, (width, height)) in pngs {
        let bytes = png.unwrap_or_else(|e| panic!("{name}: {e}"));
        let (w, h, rgb) = decode_png(&bytes);
        assert_eq!((w, h), (width, height), "{name}");
        let pixels: Vec<&[u8]> = rgb.chunks_exact(3).collect();
        let distinct: std::collections::HashSet<&[u8]> = pixels.iter().copied().collect();
        assert!(distinct.len() > 20, "{name}: {} colours", distinct.len());
        let ink = pixels.iter().filter(|p| p.iter().any(|c| *c < 200)).count() as f64
            / pixels.len() as f64;
        assert!(
            ink > 0.005 && ink < 0.6,
            "{name}: {:.3} of the pixels are drawn",
            ink
        );
        let title_band = &rgb[..(w * 30 * 3) as usize];
        assert!(
            title_band
                .chunks_exact(3)
                .any(|p| p.iter().all(|c| *c < 80)),
            "{name}: no title text"
        );
    }
}

#[test]
fn render_picks_the_format_from_the_extension() {
    let dir = std::env::temp_dir().join(format!("pendkit-plot-render-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let plot = sweep();
    plot.render(dir.join("a.svg")).expect("svg file");
    plot.render(dir.join("b.PNG")).expect("png file, any case");
    let svg = std::fs::read_to_string(dir.join("a.svg")).expect("read svg");
    parse(&svg);
    let (w, h, _) = decode_png(&std::fs::read(dir.join("b.PNG")).expect("read png"));
    assert_eq!((w, h), plot.size);
    for name in ["c.pdf", "d", "e.svg.txt"] {
        let error = plot.render(dir.join(name)).expect_err(name);
        assert!(
            matches!(error, PlotError::UnsupportedFormat { .. }),
            "{name}: {error}"
        );
        assert!(error.to_string().contains(".svg or .png"), "{error}");
        assert!(!dir.join(name).exists(), "{name} written despite the error");
    }
    std::fs::remove_dir_all(&dir).expect("clean up");
}
