//! Mode shape: side (x–z) and front (y–z) views of a suspension's bodies and wires, at rest
//! and displaced along a mode, drawn to scale.

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::axis::{AxisCoord, Scale, axis_label, format_number};
use crate::chart::{self, Panel, PanelAxes};
use crate::labels::{Label, LabelPlacer, Side};
use crate::style::{self, ANNOTATION_EM, Marker, MarkerStyle, Stroke};
use crate::{Figure, PlotError};

const FIGURE: &str = "mode shape";

/// A 3-vector (m or rad), lab axes: x along the optic axis, y transverse, z up.
type Vec3 = [f64; 3];
/// A 3x3 matrix, rows first.
type Mat3 = [[f64; 3]; 3];

/// How a body is turned: the rotation R taking body coordinates to lab coordinates (a point
/// p of the body sits at centre + R p).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Orientation {
    /// R itself, rows first; must be a rotation (orthonormal, determinant +1) to 1e-6.
    Matrix(Mat3),
    /// R = Rz(yaw) Ry(pitch) Rx(roll), angles in rad (pendkit's convention).
    YawPitchRoll {
        /// About z (rad).
        yaw: f64,
        /// About y (rad).
        pitch: f64,
        /// About x (rad).
        roll: f64,
    },
}

impl Default for Orientation {
    fn default() -> Self {
        Orientation::YawPitchRoll {
            yaw: 0.0,
            pitch: 0.0,
            roll: 0.0,
        }
    }
}

/// One of a body's own axes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BodyAxis {
    /// Body x.
    X,
    /// Body y.
    Y,
    /// Body z.
    #[default]
    Z,
}

/// The shape a body is drawn as, in body coordinates centred on the body's centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Solid {
    /// A box with these half-sizes along body x, y, z (m).
    Box {
        /// Half-sizes (m), >= 0.
        half_sizes: Vec3,
    },
    /// A cylinder of `radius` (m) and half-length `half_length` (m) along `axis`, e.g. a test
    /// mass with its axis along x.
    Cylinder {
        /// Radius (m), >= 0.
        radius: f64,
        /// Half of the length (m), >= 0.
        half_length: f64,
        /// The body axis the cylinder's axis lies along.
        axis: BodyAxis,
    },
}

/// A body to draw: its pose at rest, its shape, and its displacement along the mode.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyOutline {
    /// Name written next to the body.
    pub name: String,
    /// Centre at rest (m), lab coordinates.
    pub centre: Vec3,
    /// Orientation at rest.
    pub orientation: Orientation,
    /// Shape.
    pub solid: Solid,
    /// Displacement of the centre along the mode (m).
    pub translation: Vec3,
    /// Small rotation along the mode, about the lab x, y, z axes (rad).
    pub rotation: Vec3,
}

impl BodyOutline {
    /// A body at rest at `centre`, unrotated, not displaced.
    pub fn new(name: impl Into<String>, centre: Vec3, solid: Solid) -> Self {
        BodyOutline {
            name: name.into(),
            centre,
            orientation: Orientation::default(),
            solid,
            translation: [0.0; 3],
            rotation: [0.0; 3],
        }
    }
}

/// A wire drawn as a straight segment between its attachment points, each with its own
/// displacement along the mode.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct WireSegment {
    /// Upper attachment point at rest (m).
    pub top: Vec3,
    /// Lower attachment point at rest (m).
    pub bottom: Vec3,
    /// Displacement of the upper point along the mode (m).
    pub top_displacement: Vec3,
    /// Displacement of the lower point along the mode (m).
    pub bottom_displacement: Vec3,
}

/// How much the mode's displacements are magnified in the drawing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Amplitude {
    /// Scale so that the largest displacement of any drawn point is this fraction of the
    /// drawing's largest dimension (0 < fraction <= 1; default 0.1).
    Auto {
        /// Fraction of the drawing's size.
        fraction: f64,
    },
    /// Multiply every displacement by this factor (>= 0).
    Factor(f64),
}

impl Default for Amplitude {
    fn default() -> Self {
        Amplitude::Auto { fraction: 0.1 }
    }
}

/// Side view (x–z) and front view (y–z) of bodies and wires, at rest (light) and displaced
/// along a mode (dark), with equal scales on both axes and in both views so that shapes are
/// not distorted. The magnification of the displacements is stated under the title.
///
/// Body rotations are applied exactly (as rotations by the magnified angle), so a body is
/// never sheared however large the magnification. Every coordinate must be finite and every
/// size non-negative: anything else is an error naming the body or wire.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeShapePlot {
    /// Figure title (may be empty), e.g. `"mode 7: 0.98 Hz, P"`.
    pub title: String,
    /// The bodies, drawn in order.
    pub bodies: Vec<BodyOutline>,
    /// The wires.
    pub wires: Vec<WireSegment>,
    /// Magnification of the displacements.
    pub amplitude: Amplitude,
    /// Width and height, pixels (default 960 x 720).
    pub size: (u32, u32),
}

impl ModeShapePlot {
    /// A mode-shape figure with automatic magnification; push bodies and wires.
    pub fn new(title: impl Into<String>) -> Self {
        ModeShapePlot {
            title: title.into(),
            bodies: Vec::new(),
            wires: Vec::new(),
            amplitude: Amplitude::default(),
            size: (960, 720),
        }
    }
}

fn add(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn scale(a: Vec3, s: f64) -> Vec3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm(a: Vec3) -> f64 {
    a[0].hypot(a[1]).hypot(a[2])
}

fn mat_vec(m: &Mat3, v: Vec3) -> Vec3 {
    [
        m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
        m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
        m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
    ]
}

fn mat_mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut out = [[0.0; 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, value) in row.iter_mut().enumerate() {
            *value = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    out
}

/// Rotation by the vector `v` (axis v/|v|, angle |v| rad), by Rodrigues' formula.
fn rotation_by(v: Vec3) -> Mat3 {
    let angle = norm(v);
    if angle == 0.0 {
        return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    }
    let [x, y, z] = scale(v, 1.0 / angle);
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [c + x * x * t, x * y * t - z * s, x * z * t + y * s],
        [y * x * t + z * s, c + y * y * t, y * z * t - x * s],
        [z * x * t - y * s, z * y * t + x * s, c + z * z * t],
    ]
}

impl Orientation {
    /// The body-to-lab rotation matrix.
    fn matrix(&self) -> Mat3 {
        match *self {
            Orientation::Matrix(m) => m,
            Orientation::YawPitchRoll { yaw, pitch, roll } => {
                let (sy, cy) = yaw.sin_cos();
                let (sp, cp) = pitch.sin_cos();
                let (sr, cr) = roll.sin_cos();
                let rz = [[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]];
                let ry = [[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]];
                let rx = [[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]];
                mat_mul(&mat_mul(&rz, &ry), &rx)
            }
        }
    }
}

/// Points on the solid's surface (body coordinates) whose projections' convex hull is the
/// solid's silhouette: a box's corners; a cylinder's two end circles, 48 points each.
fn surface_points(solid: &Solid) -> Vec<Vec3> {
    match *solid {
        Solid::Box {
            half_sizes: [a, b, c],
        } => {
            let mut corners = Vec::with_capacity(8);
            for sx in [-a, a] {
                for sy in [-b, b] {
                    for sz in [-c, c] {
                        corners.push([sx, sy, sz]);
                    }
                }
            }
            corners
        }
        Solid::Cylinder {
            radius,
            half_length,
            axis,
        } => {
            const RIM: usize = 48;
            let mut points = Vec::with_capacity(2 * RIM);
            for end in [-half_length, half_length] {
                for k in 0..RIM {
                    let angle = 2.0 * std::f64::consts::PI * k as f64 / RIM as f64;
                    let (u, v) = (radius * angle.cos(), radius * angle.sin());
                    points.push(match axis {
                        BodyAxis::X => [end, u, v],
                        BodyAxis::Y => [v, end, u],
                        BodyAxis::Z => [u, v, end],
                    });
                }
            }
            points
        }
    }
}

/// Convex hull of 2-D points, counter-clockwise (Andrew's monotone chain); duplicate points
/// collapse, a single point stays one point.
fn convex_hull(mut points: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    points.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    points.dedup();
    if points.len() < 3 {
        return points;
    }
    let turn = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let mut hull: Vec<(f64, f64)> = Vec::with_capacity(points.len() + 1);
    for pass in 0..2 {
        let start = hull.len();
        let ordered: Box<dyn Iterator<Item = &(f64, f64)>> = if pass == 0 {
            Box::new(points.iter())
        } else {
            Box::new(points.iter().rev())
        };
        for &p in ordered {
            while hull.len() >= start + 2
                && turn(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

/// The two views: which lab axis is horizontal (x or y); z is always vertical.
#[derive(Debug, Clone, Copy)]
enum View {
    Side,
    Front,
}

impl View {
    fn project(self, p: Vec3) -> (f64, f64) {
        match self {
            View::Side => (p[0], p[2]),
            View::Front => (p[1], p[2]),
        }
    }

    fn title(self) -> &'static str {
        match self {
            View::Side => "side view (x–z)",
            View::Front => "front view (y–z)",
        }
    }

    fn horizontal_label(self) -> String {
        match self {
            View::Side => axis_label("x", "m"),
            View::Front => axis_label("y", "m"),
        }
    }
}

/// Everything drawn, in lab coordinates: body surface points and wire ends, at rest and
/// displaced by the chosen magnification.
struct Scene {
    rest_bodies: Vec<Vec<Vec3>>,
    moved_bodies: Vec<Vec<Vec3>>,
    rest_wires: Vec<(Vec3, Vec3)>,
    moved_wires: Vec<(Vec3, Vec3)>,
    magnification: f64,
    /// Largest displacement of a drawn point before magnification (m).
    largest: f64,
}

impl ModeShapePlot {
    fn validate(&self) -> Result<(), PlotError> {
        if self.bodies.is_empty() && self.wires.is_empty() {
            return Err(PlotError::NothingToPlot {
                figure: FIGURE,
                reason: "no bodies and no wires".to_string(),
            });
        }
        let finite = |what: String, values: &[f64]| -> Result<(), PlotError> {
            match values.iter().find(|v| !v.is_finite()) {
                Some(&value) => Err(PlotError::NotFinite {
                    figure: FIGURE,
                    what,
                    value,
                }),
                None => Ok(()),
            }
        };
        let invalid = |what: String, reason: String| PlotError::InvalidInput {
            figure: FIGURE,
            what,
            reason,
        };
        for body in &self.bodies {
            let name = &body.name;
            finite(format!("centre of body `{name}`"), &body.centre)?;
            finite(format!("translation of body `{name}`"), &body.translation)?;
            finite(format!("rotation of body `{name}`"), &body.rotation)?;
            let r = match body.orientation {
                Orientation::Matrix(m) => {
                    finite(format!("orientation of body `{name}`"), m.as_flattened())?;
                    m
                }
                Orientation::YawPitchRoll { yaw, pitch, roll } => {
                    finite(format!("orientation of body `{name}`"), &[yaw, pitch, roll])?;
                    body.orientation.matrix()
                }
            };
            if !is_rotation(&r) {
                return Err(invalid(
                    format!("orientation of body `{name}`"),
                    "the matrix is not a rotation (orthonormal with determinant +1, to 1e-6)"
                        .to_string(),
                ));
            }
            let sizes: Vec<f64> = match body.solid {
                Solid::Box { half_sizes } => half_sizes.to_vec(),
                Solid::Cylinder {
                    radius,
                    half_length,
                    ..
                } => vec![radius, half_length],
            };
            finite(format!("size of body `{name}`"), &sizes)?;
            if let Some(size) = sizes.iter().find(|s| **s < 0.0) {
                return Err(invalid(
                    format!("size of body `{name}`"),
                    format!("{size} m is negative"),
                ));
            }
        }
        for (index, wire) in self.wires.iter().enumerate() {
            let values = [
                wire.top,
                wire.bottom,
                wire.top_displacement,
                wire.bottom_displacement,
            ];
            finite(format!("end points of wire {index}"), values.as_flattened())?;
        }
        match self.amplitude {
            Amplitude::Auto { fraction } if !(fraction > 0.0 && fraction <= 1.0) => Err(invalid(
                "amplitude fraction".to_string(),
                format!("{fraction} is not in (0, 1]"),
            )),
            Amplitude::Factor(factor) if !(factor.is_finite() && factor >= 0.0) => Err(invalid(
                "amplitude factor".to_string(),
                format!("{factor} is not finite and >= 0"),
            )),
            _ => Ok(()),
        }
    }

    /// The bodies' and wires' points at rest and displaced.
    fn scene(&self) -> Scene {
        let body_points: Vec<(Mat3, Vec<Vec3>)> = self
            .bodies
            .iter()
            .map(|b| (b.orientation.matrix(), surface_points(&b.solid)))
            .collect();
        let rest_bodies: Vec<Vec<Vec3>> = self
            .bodies
            .iter()
            .zip(&body_points)
            .map(|(b, (r, local))| {
                local
                    .iter()
                    .map(|p| add(b.centre, mat_vec(r, *p)))
                    .collect()
            })
            .collect();
        let rest_wires: Vec<(Vec3, Vec3)> = self.wires.iter().map(|w| (w.top, w.bottom)).collect();

        // Displacements to first order: a body point moves by t + θ × (R p).
        let mut largest = 0.0f64;
        for (b, (r, local)) in self.bodies.iter().zip(&body_points) {
            for p in local {
                let moved = add(b.translation, cross(b.rotation, mat_vec(r, *p)));
                largest = largest.max(norm(moved));
            }
            largest = largest.max(norm(b.translation));
        }
        for w in &self.wires {
            largest = largest
                .max(norm(w.top_displacement))
                .max(norm(w.bottom_displacement));
        }
        let extent = drawing_size(
            rest_bodies
                .iter()
                .flatten()
                .copied()
                .chain(rest_wires.iter().flat_map(|(a, b)| [*a, *b])),
        );
        let magnification = match self.amplitude {
            Amplitude::Factor(factor) => factor,
            Amplitude::Auto { .. } if largest == 0.0 => 0.0,
            Amplitude::Auto { fraction } if extent > 0.0 => fraction * extent / largest,
            // A drawing with no extent (points only): show the displacement as it is.
            Amplitude::Auto { .. } => 1.0,
        };
        let moved_bodies = self
            .bodies
            .iter()
            .zip(&body_points)
            .map(|(b, (r, local))| {
                let turned = mat_mul(&rotation_by(scale(b.rotation, magnification)), r);
                let centre = add(b.centre, scale(b.translation, magnification));
                local
                    .iter()
                    .map(|p| add(centre, mat_vec(&turned, *p)))
                    .collect()
            })
            .collect();
        let moved_wires = self
            .wires
            .iter()
            .map(|w| {
                (
                    add(w.top, scale(w.top_displacement, magnification)),
                    add(w.bottom, scale(w.bottom_displacement, magnification)),
                )
            })
            .collect();
        Scene {
            rest_bodies,
            moved_bodies,
            rest_wires,
            moved_wires,
            magnification,
            largest,
        }
    }

    /// The line under the title that states the magnification.
    fn caption(&self, scene: &Scene) -> String {
        if scene.largest == 0.0 {
            return "no displacement in the drawn parts (rest position only)".to_string();
        }
        let factor = format_number(scene.magnification, 3);
        match self.amplitude {
            Amplitude::Auto { fraction } => format!(
                "displacements magnified ×{factor}, the largest to {} % of the drawing's size \
                 (light: at rest; dark: displaced)",
                format_number(100.0 * fraction, 3)
            ),
            Amplitude::Factor(_) => {
                format!("displacements magnified ×{factor} (light: at rest; dark: displaced)")
            }
        }
    }
}

/// Whether `r` is orthonormal with determinant +1, to 1e-6.
fn is_rotation(r: &Mat3) -> bool {
    let mut worst = 0.0f64;
    for i in 0..3 {
        for j in 0..3 {
            let dot: f64 = (0..3).map(|k| r[k][i] * r[k][j]).sum();
            let expected = if i == j { 1.0 } else { 0.0 };
            worst = worst.max((dot - expected).abs());
        }
    }
    let det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
        - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
        + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
    worst < 1e-6 && det > 0.0
}

/// Largest extent along x, y or z of a set of points (m).
fn drawing_size(points: impl Iterator<Item = Vec3>) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (0..3)
        .map(|k| hi[k] - lo[k])
        .filter(|d| d.is_finite())
        .fold(0.0, f64::max)
}

/// Horizontal and vertical bounds (m) of everything a view shows.
#[derive(Debug, Clone, Copy)]
struct ViewBounds {
    horizontal: (f64, f64),
    vertical: (f64, f64),
}

impl ViewBounds {
    fn spans(&self) -> (f64, f64) {
        (
            self.horizontal.1 - self.horizontal.0,
            self.vertical.1 - self.vertical.0,
        )
    }
}

/// The bounds of everything a view shows.
fn view_bounds(scene: &Scene, view: View) -> ViewBounds {
    let mut h = (f64::INFINITY, f64::NEG_INFINITY);
    let mut v = (f64::INFINITY, f64::NEG_INFINITY);
    let bodies = scene
        .rest_bodies
        .iter()
        .chain(&scene.moved_bodies)
        .flatten()
        .copied();
    let wires = scene
        .rest_wires
        .iter()
        .chain(&scene.moved_wires)
        .flat_map(|(a, b)| [*a, *b]);
    for p in bodies.chain(wires) {
        let (x, y) = view.project(p);
        h = (h.0.min(x), h.1.max(x));
        v = (v.0.min(y), v.1.max(y));
    }
    ViewBounds {
        horizontal: h,
        vertical: v,
    }
}

/// Axes of one view: the data centred, `pixels_per_metre` along both axes.
fn view_axes(
    view: View,
    bounds: ViewBounds,
    (width, height): (u32, u32),
    pixels_per_metre: f64,
) -> Option<PanelAxes> {
    let half_width = 0.5 * f64::from(width.max(1)) / pixels_per_metre;
    let half_height = 0.5 * f64::from(height.max(1)) / pixels_per_metre;
    let (h, v) = (bounds.horizontal, bounds.vertical);
    let (hc, vc) = (0.5 * (h.0 + h.1), 0.5 * (v.0 + v.1));
    let x = AxisCoord::linear(hc - half_width, hc + half_width)?;
    let y = AxisCoord::linear(vc - half_height, vc + half_height)?;
    Some(PanelAxes::new(
        (x, y),
        (view.horizontal_label(), axis_label("z", "m")),
        (Scale::Linear, Scale::Linear),
    ))
}

/// The common scale (pixels per metre) at which both views fit their panels, with a margin
/// of 6 % of the largest span around the data.
fn common_scale(bounds: &[ViewBounds], panels: &[(u32, u32)]) -> f64 {
    let spans: Vec<(f64, f64)> = bounds.iter().map(ViewBounds::spans).collect();
    let largest = spans.iter().fold(0.0f64, |m, (a, b)| m.max(*a).max(*b));
    let margin = if largest > 0.0 { 0.12 * largest } else { 1.0 };
    spans
        .iter()
        .zip(panels)
        .map(|((hs, vs), (w, h))| {
            (f64::from(*w) / (hs + margin)).min(f64::from(*h) / (vs + margin))
        })
        .fold(f64::INFINITY, f64::min)
}

const REST_FILL: RGBColor = RGBColor(228, 228, 228);
const REST_LINE: RGBColor = RGBColor(175, 175, 175);
const MOVED_FILL: RGBAColor = RGBAColor(31, 119, 180, 0.25);
const MOVED_LINE: RGBColor = RGBColor(20, 60, 130);
const MOVED_WIRE: RGBColor = RGBColor(40, 40, 40);

/// Draws one body silhouette (fill and outline) in pixels.
fn draw_silhouette<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    hull: &[(i32, i32)],
    fill: ShapeStyle,
    outline: &Stroke,
) -> Result<(), PlotError> {
    match hull {
        [] => Ok(()),
        [single] => style::draw_pixel_marker(
            area,
            *single,
            &MarkerStyle::new(Marker::Square, outline.color, 2, true),
        ),
        [a, b] => style::draw_pixel_line(area, &[*a, *b], outline),
        _ => {
            area.draw(&Polygon::new(hull.to_vec(), fill))?;
            let mut closed = hull.to_vec();
            closed.push(hull[0]);
            style::draw_pixel_line(area, &closed, outline)
        }
    }
}

/// Pixel silhouette of a body's points in a view.
fn pixel_hull<DB: DrawingBackend>(
    panel: &Panel<'_, DB>,
    view: View,
    points: &[Vec3],
) -> Vec<(i32, i32)> {
    let hull = convex_hull(points.iter().map(|p| view.project(*p)).collect());
    let mut pixels: Vec<(i32, i32)> = hull.iter().map(|&(x, y)| panel.to_pixel(x, y)).collect();
    pixels.dedup();
    pixels
}

fn draw_view<DB: DrawingBackend>(
    panel: &Panel<'_, DB>,
    view: View,
    scene: &Scene,
    names: &[&str],
) -> Result<(), PlotError> {
    let area = panel.area;
    let rest_wire = Stroke::solid(REST_LINE, 1);
    let rest_outline = Stroke::solid(REST_LINE, 1);
    let moved_wire = Stroke::solid(MOVED_WIRE, 2);
    let moved_outline = Stroke::solid(MOVED_LINE, 2);
    let wire_pixels = |(a, b): &(Vec3, Vec3)| {
        let (a, b) = (view.project(*a), view.project(*b));
        [panel.to_pixel(a.0, a.1), panel.to_pixel(b.0, b.1)]
    };
    for wire in &scene.rest_wires {
        style::draw_pixel_line(area, &wire_pixels(wire), &rest_wire)?;
    }
    let rest_hulls: Vec<Vec<(i32, i32)>> = scene
        .rest_bodies
        .iter()
        .map(|points| pixel_hull(panel, view, points))
        .collect();
    for hull in &rest_hulls {
        draw_silhouette(area, hull, REST_FILL.filled(), &rest_outline)?;
    }
    for wire in &scene.moved_wires {
        style::draw_pixel_line(area, &wire_pixels(wire), &moved_wire)?;
    }
    for points in &scene.moved_bodies {
        let hull = pixel_hull(panel, view, points);
        draw_silhouette(area, &hull, MOVED_FILL.filled(), &moved_outline)?;
    }
    // Names to the right of the bodies at rest (left if there is no room).
    let mut placer = LabelPlacer::new(panel.plot_rect());
    let label_style = style::text(ANNOTATION_EM);
    for (hull, name) in rest_hulls.iter().zip(names) {
        let Some(right) = hull.iter().map(|p| p.0).max() else {
            continue;
        };
        let left = hull.iter().map(|p| p.0).min().unwrap_or(right);
        let (top, bottom) = (
            hull.iter().map(|p| p.1).min().unwrap_or(0),
            hull.iter().map(|p| p.1).max().unwrap_or(0),
        );
        let middle = (top + bottom) / 2;
        let half_width = (right - left) / 2;
        let label = Label {
            text: name,
            style: &label_style,
            at: ((left + right) / 2, middle),
            gap: half_width + 8,
        };
        placer.place(area, &label, &[Side::Right, Side::Left], false)?;
    }
    Ok(())
}

impl Figure for ModeShapePlot {
    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        self.validate()?;
        let scene = self.scene();
        let body = style::draw_title(area, &self.title, Some(&self.caption(&scene)))?;
        let views = [View::Side, View::Front];
        let panels = body.split_evenly((1, 2));
        let mut titled = Vec::with_capacity(2);
        for (panel, view) in panels.iter().zip(views) {
            titled.push(panel.titled(view.title(), style::text(style::AXIS_TITLE_EM))?);
        }
        // Both views project the same points, so they share the vertical (z) range and,
        // at one common scale, line up side by side.
        let bounds: Vec<ViewBounds> = views.iter().map(|v| view_bounds(&scene, *v)).collect();
        // Lay the panels out, read the plotting areas' sizes, fit the common scale, and
        // repeat until the layout (which depends on the tick labels) stops changing.
        let nothing = || PlotError::NothingToPlot {
            figure: FIGURE,
            reason: "the drawing has no finite extent".to_string(),
        };
        let mut dims: Vec<(u32, u32)> = titled.iter().map(|a| a.dim_in_pixel()).collect();
        let mut panels = Vec::with_capacity(2);
        for _ in 0..4 {
            let pixels_per_metre = common_scale(&bounds, &dims);
            panels = views
                .iter()
                .zip(bounds.iter().copied())
                .zip(&dims)
                .zip(&titled)
                .map(|(((view, b), d), area)| {
                    let axes = view_axes(*view, b, *d, pixels_per_metre).ok_or_else(nothing)?;
                    chart::layout(area, axes)
                })
                .collect::<Result<Vec<_>, _>>()?;
            let new_dims: Vec<(u32, u32)> = panels.iter().map(Panel::plot_size).collect();
            if new_dims == dims {
                break;
            }
            dims = new_dims;
        }
        let names: Vec<&str> = self.bodies.iter().map(|b| b.name.as_str()).collect();
        for (panel, view) in panels.iter_mut().zip(views) {
            panel.draw_mesh()?;
            draw_view(panel, view, &scene, &names)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &Mat3, b: &Mat3) -> bool {
        a.iter()
            .flatten()
            .zip(b.iter().flatten())
            .all(|(x, y)| (x - y).abs() < 1e-12)
    }

    #[test]
    fn yaw_pitch_roll_composes_z_y_x() {
        // A quarter turn of yaw takes body x to lab y; of pitch, body x to lab -z; of roll,
        // body y to lab z (right-hand rule about each axis).
        let q = std::f64::consts::FRAC_PI_2;
        let yaw = Orientation::YawPitchRoll {
            yaw: q,
            pitch: 0.0,
            roll: 0.0,
        }
        .matrix();
        let pitch = Orientation::YawPitchRoll {
            yaw: 0.0,
            pitch: q,
            roll: 0.0,
        }
        .matrix();
        let roll = Orientation::YawPitchRoll {
            yaw: 0.0,
            pitch: 0.0,
            roll: q,
        }
        .matrix();
        let near = |a: Vec3, b: Vec3| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-12);
        assert!(near(mat_vec(&yaw, [1.0, 0.0, 0.0]), [0.0, 1.0, 0.0]));
        assert!(near(mat_vec(&pitch, [1.0, 0.0, 0.0]), [0.0, 0.0, -1.0]));
        assert!(near(mat_vec(&roll, [0.0, 1.0, 0.0]), [0.0, 0.0, 1.0]));
        // Order: R = Rz Ry Rx, checked against the product of the three.
        let all = Orientation::YawPitchRoll {
            yaw: 0.3,
            pitch: -0.2,
            roll: 0.1,
        }
        .matrix();
        let product = mat_mul(
            &mat_mul(
                &Orientation::YawPitchRoll {
                    yaw: 0.3,
                    pitch: 0.0,
                    roll: 0.0,
                }
                .matrix(),
                &Orientation::YawPitchRoll {
                    yaw: 0.0,
                    pitch: -0.2,
                    roll: 0.0,
                }
                .matrix(),
            ),
            &Orientation::YawPitchRoll {
                yaw: 0.0,
                pitch: 0.0,
                roll: 0.1,
            }
            .matrix(),
        );
        assert!(close(&all, &product));
        assert!(is_rotation(&all));
    }

    #[test]
    fn rodrigues_matches_the_axis_rotations() {
        // A rotation vector along z is a yaw by its length.
        let by_vector = rotation_by([0.0, 0.0, 0.7]);
        let by_yaw = Orientation::YawPitchRoll {
            yaw: 0.7,
            pitch: 0.0,
            roll: 0.0,
        }
        .matrix();
        assert!(close(&by_vector, &by_yaw));
        assert!(is_rotation(&rotation_by([0.3, -1.2, 2.0])));
        assert!(!is_rotation(&[
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, -1.0]
        ]));
    }

    #[test]
    fn hull_of_a_box_seen_from_the_side_is_its_rectangle() {
        let corners = surface_points(&Solid::Box {
            half_sizes: [1.0, 2.0, 3.0],
        });
        let hull = convex_hull(corners.iter().map(|p| View::Side.project(*p)).collect());
        // Counter-clockwise from the lowest-left corner.
        assert_eq!(
            hull,
            vec![(-1.0, -3.0), (1.0, -3.0), (1.0, 3.0), (-1.0, 3.0)]
        );
        assert_eq!(convex_hull(vec![(0.0, 0.0), (0.0, 0.0)]), vec![(0.0, 0.0)]);
    }

    #[test]
    fn auto_magnification_brings_the_largest_displacement_to_the_fraction() {
        // A 1 m tall wire whose bottom moves 1 mm along x: magnified to 10 % of 1 m.
        let mut plot = ModeShapePlot::new("");
        plot.wires.push(WireSegment {
            top: [0.0, 0.0, 1.0],
            bottom: [0.0, 0.0, 0.0],
            top_displacement: [0.0; 3],
            bottom_displacement: [1e-3, 0.0, 0.0],
        });
        let scene = plot.scene();
        assert!((scene.magnification - 100.0).abs() < 1e-9);
        assert!((scene.moved_wires[0].1[0] - 0.1).abs() < 1e-12);
        // A rotation displaces body points by θ × r: a 0.2 m half-length box turned 1 mrad
        // in pitch moves its corners by 1e-3 * |(±0.2, 0, ±0.1)| = 2.236e-4 m.
        let mut plot = ModeShapePlot::new("");
        let mut body = BodyOutline::new(
            "m",
            [0.0; 3],
            Solid::Box {
                half_sizes: [0.2, 0.1, 0.1],
            },
        );
        body.rotation = [0.0, 1e-3, 0.0];
        plot.bodies.push(body);
        let scene = plot.scene();
        assert!(
            (scene.largest - 1e-3 * 0.05f64.sqrt()).abs() < 1e-15,
            "{}",
            scene.largest
        );
    }
}
