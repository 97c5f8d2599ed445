//! Helpers shared by the integration tests: reading back the SVG and PNG the crate writes,
//! and small figures to render.

use pendkit_plot::{
    Axis, BodePlot, BodeSeries, BodyOutline, Contribution, LinePlot, ModeChart, ModeMarker,
    ModeShapePlot, NoiseBudget, Scale, Series, Solid, TradeoffChart, TradeoffPoint, WireSegment,
};

/// A parsed SVG document; panics with the parser's message if it is not well-formed XML.
pub fn parse(svg: &str) -> roxmltree::Document<'_> {
    let doc = roxmltree::Document::parse(svg).unwrap_or_else(|e| panic!("SVG is not XML: {e}"));
    assert_eq!(doc.root_element().tag_name().name(), "svg");
    doc
}

/// Every `<text>` element's content, trimmed.
pub fn texts(doc: &roxmltree::Document<'_>) -> Vec<String> {
    doc.descendants()
        .filter(|n| n.has_tag_name("text"))
        .filter_map(|n| n.text().map(|t| t.trim().to_string()))
        .collect()
}

/// A `points` attribute as pixel coordinates.
pub fn points(attribute: &str) -> Vec<(f64, f64)> {
    attribute
        .split_whitespace()
        .filter_map(|pair| {
            let (x, y) = pair.split_once(',')?;
            Some((x.parse().ok()?, y.parse().ok()?))
        })
        .collect()
}

/// The points of every `tag` element (polyline, polygon) whose attribute `key` is `value`.
pub fn shapes_with(
    doc: &roxmltree::Document<'_>,
    tag: &str,
    key: &str,
    value: &str,
) -> Vec<Vec<(f64, f64)>> {
    doc.descendants()
        .filter(|n| n.has_tag_name(tag) && n.attribute(key) == Some(value))
        .map(|n| points(n.attribute("points").unwrap_or("")))
        .collect()
}

/// Text elements with their (x, y) attribute and anchor.
pub fn placed_texts(doc: &roxmltree::Document<'_>) -> Vec<(String, f64, f64, String)> {
    doc.descendants()
        .filter(|n| n.has_tag_name("text"))
        .map(|n| {
            let number = |k: &str| {
                n.attribute(k)
                    .and_then(|v| v.parse().ok())
                    .unwrap_or(f64::NAN)
            };
            (
                n.text().unwrap_or("").trim().to_string(),
                number("x"),
                number("y"),
                n.attribute("text-anchor").unwrap_or("").to_string(),
            )
        })
        .collect()
}

/// A decoded 8-bit RGB PNG: width, height, pixels.
pub fn decode_png(bytes: &[u8]) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().expect("PNG header");
    let mut buffer = vec![0; reader.output_buffer_size().expect("buffer size")];
    let info = reader.next_frame(&mut buffer).expect("PNG frame");
    assert_eq!(info.color_type, png::ColorType::Rgb);
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    buffer.truncate(info.buffer_size());
    (info.width, info.height, buffer)
}

/// Log-spaced values from `from` to `to`.
pub fn logspace(from: f64, to: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| from * (to / from).powf(i as f64 / (n - 1).max(1) as f64))
        .collect()
}

/// A single pendulum's response to support motion, f0 = 1 Hz, loss angle 0.01:
/// w0²(1 + iφ) / (w0²(1 + iφ) - w²).
pub fn pendulum(f: f64) -> (f64, f64) {
    let (w2, w02, phi) = (
        (2.0 * std::f64::consts::PI * f).powi(2),
        (2.0 * std::f64::consts::PI).powi(2),
        0.01,
    );
    let (dr, di) = (w02 - w2, w02 * phi);
    let d = dr * dr + di * di;
    (
        (w02 * dr + w02 * phi * di) / d,
        (w02 * phi * dr - w02 * di) / d,
    )
}

pub fn bode() -> BodePlot {
    let f = logspace(0.1, 100.0, 200);
    let mut plot = BodePlot::new("Pendulum", "|x3/x00|", "m/m");
    plot.series.push(BodeSeries::new(
        "x3/x00",
        f.clone(),
        f.iter().map(|&f| pendulum(f)).collect(),
    ));
    plot.series.push(BodeSeries::new(
        "half",
        f.clone(),
        f.iter()
            .map(|&f| {
                let (re, im) = pendulum(f);
                (0.5 * re, 0.5 * im)
            })
            .collect(),
    ));
    plot
}

pub fn noise() -> NoiseBudget {
    let f = logspace(1.0, 1000.0, 100);
    let a: Vec<f64> = f.iter().map(|f| 1e-18 / f).collect();
    let b: Vec<f64> = f.iter().map(|f| 1e-20 / f.sqrt()).collect();
    let total = a.iter().zip(&b).map(|(x, y)| x.hypot(*y)).collect();
    let mut budget = NoiseBudget::new(
        "Budget",
        "displacement ASD",
        "m/√Hz",
        f,
        Contribution::new("total", total),
    );
    budget
        .contributions
        .push(Contribution::new("fibre_bending", a));
    budget.contributions.push(Contribution::new("blade_n", b));
    budget
}

pub fn modes() -> ModeChart {
    let mut modes: Vec<ModeMarker> = [
        (0.43, "L"),
        (1.0, "L"),
        (0.56, "P"),
        (2.6, "P"),
        (6.9, "V"),
        (500.0, "violin"),
    ]
    .iter()
    .map(|&(f, family)| ModeMarker::new(f, family))
    .collect();
    modes.push(ModeMarker {
        frequency_hz: -0.05,
        family: "Y".into(),
        label: Some("unstable Y".into()),
        unstable: true,
    });
    ModeChart::new("Modes", modes)
}

/// One box body (half-sizes 0.3, 0.2, 0.1 m) hanging from a 0.9 m wire, moved 1 mm in x.
pub fn mode_shape() -> ModeShapePlot {
    let mut plot = ModeShapePlot::new("Pendulum mode");
    let mut body = BodyOutline::new(
        "mass",
        [0.0, 0.0, 0.0],
        Solid::Box {
            half_sizes: [0.3, 0.2, 0.1],
        },
    );
    body.translation = [1e-3, 0.0, 0.0];
    plot.bodies.push(body);
    plot.wires.push(WireSegment {
        top: [0.0, 0.0, 1.0],
        bottom: [0.0, 0.0, 0.1],
        top_displacement: [0.0; 3],
        bottom_displacement: [1e-3, 0.0, 0.0],
    });
    plot
}

pub fn tradeoff() -> TradeoffChart {
    let points = [
        ("fast", 0.001, 0.1),
        ("middle", 0.01, 0.001),
        ("slow, worse", 0.1, 0.01),
        ("reference", 1.0, 0.0),
    ]
    .iter()
    .map(|&(name, s, e)| TradeoffPoint::new(name, s, e))
    .collect();
    let mut chart = TradeoffChart::new("Trade-off", points);
    chart.tolerance = Some(1e-3);
    chart
}

pub fn sweep() -> LinePlot {
    let x: Vec<f64> = (1..=20).map(f64::from).collect();
    let mut plot = LinePlot::new(
        "Sweep",
        Axis::new("fibre radius", "mm", Scale::Linear),
        Axis::new("frequency", "Hz", Scale::Log),
    );
    plot.series.push(Series::new(
        "violin",
        x.clone(),
        x.iter().map(|r| 500.0 * r).collect(),
    ));
    plot.series.push(Series::new(
        "bounce",
        x.clone(),
        x.iter().map(|r| 9.0 * r).collect(),
    ));
    plot
}
