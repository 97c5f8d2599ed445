//! Figures of a run, built from its results with pendkit-plot: Bode plots of transfer
//! functions, noise budgets, mode charts and mode shapes. `tf`, `noise`, `modes`, `sweep`
//! and `report` share these, so a figure looks the same whichever command draws it.

use nalgebra::Vector3;
use pendkit::NoiseOptions;
use pendkit::dynamics::Mode;
use pendkit::noise::ThermalNoise;
use pendkit::system::{BodyId, Shape};
use pendkit_plot::{
    BodeSeries, BodyAxis, BodyOutline, Contribution, ModeChart, ModeMarker, ModeShapePlot,
    NoiseBudget, Orientation, Solid, WireSegment,
};

use crate::common::Run;
use crate::error::CliError;

/// One transfer function of a Bode plot: its display name, unit and values.
pub struct Response {
    /// Legend name, `output/input` in the display names.
    pub name: String,
    /// Unit, e.g. `m/m`.
    pub unit: String,
    /// Complex values at the plot's frequencies.
    pub values: Vec<pendkit::nalgebra::Complex<f64>>,
}

/// A Bode plot of responses that share one unit (an error names the units otherwise).
pub fn bode(
    title: &str,
    freqs: &[f64],
    responses: &[Response],
) -> Result<pendkit_plot::BodePlot, CliError> {
    let Some(first) = responses.first() else {
        return Err(CliError::usage("--plot: no transfer function to plot"));
    };
    if let Some(other) = responses.iter().find(|r| r.unit != first.unit) {
        return Err(CliError::usage(format!(
            "--plot: one Bode plot needs one unit, but {} is in {} and {} in {} (plot them separately)",
            first.name, first.unit, other.name, other.unit
        )));
    }
    let quantity = if responses.len() == 1 {
        format!("|{}|", first.name)
    } else {
        "|H|".to_string()
    };
    let mut plot = pendkit_plot::BodePlot::new(title, quantity, first.unit.clone());
    for r in responses {
        plot.series.push(BodeSeries::new(
            r.name.clone(),
            freqs.to_vec(),
            r.values.iter().map(|z| (z.re, z.im)).collect(),
        ));
    }
    Ok(plot)
}

/// The thermal noise of `output` at `freqs` by damping tag, as computed for a budget.
pub fn noise(run: &Run, output: &str, freqs: &[f64]) -> Result<ThermalNoise, CliError> {
    Ok(run
        .result
        .noise_with(output, freqs, &NoiseOptions::default())?)
}

/// A noise budget: the total ASD and each damping tag's, log-log; tags that contribute
/// nothing anywhere are left out.
pub fn noise_budget(run: &Run, output: &str, freqs: &[f64], noise: &ThermalNoise) -> NoiseBudget {
    let unit = run.result.output_unit(output).unwrap_or_default();
    let quantity = match unit.as_str() {
        "rad" => "angle ASD",
        _ => "displacement ASD",
    };
    let mut budget = NoiseBudget::new(
        format!(
            "Thermal noise of {}: {}, {} K",
            run.port(output),
            run.heading(),
            run.result.system.temperature
        ),
        quantity,
        format!("{unit}/√Hz"),
        freqs.to_vec(),
        Contribution::new("total", noise.asd()),
    );
    for (tag, asd) in noise.asd_by_tag() {
        if asd.iter().any(|&a| a > 0.0) {
            budget.contributions.push(Contribution::new(tag, asd));
        }
    }
    budget
}

/// The mode chart: every mode's frequency in a row by family (L, T, V, R, P, Y, violin).
pub fn mode_chart(run: &Run) -> ModeChart {
    let modes = run
        .result
        .modes
        .modes
        .iter()
        .map(|m| ModeMarker {
            frequency_hz: m.hz,
            family: run.result.mode_family(m),
            label: None,
            unstable: !m.is_stable(),
        })
        .collect();
    ModeChart::new(
        format!(
            "Normal modes: {} ({} modes)",
            run.heading(),
            run.result.modes.modes.len()
        ),
        modes,
    )
}

/// Displacement (m) of a point `p` (body coordinates, m) of body `b` and the body's small
/// rotation about the lab x, y, z axes (rad), per unit modal amplitude of `mode` (floats
/// held: they follow the variables and are not drawn).
fn point_motion(run: &Run, b: BodyId, p: &Vector3<f64>, mode: &Mode) -> ([f64; 3], [f64; 3]) {
    let r = &run.result;
    let jac = r.system.bodies[b]
        .frame
        .jacobian(&r.assembled.equilibrium.coords, p);
    let mut translation = Vector3::zeros();
    let mut rotation = Vector3::zeros();
    for (k, &g) in r.assembled.layout.variables.iter().enumerate() {
        let amplitude = mode.vector.get(k).copied().unwrap_or(0.0);
        translation += jac.position.column(g) * amplitude;
        rotation += jac.omega_space.column(g) * amplitude;
    }
    (translation.into(), rotation.into())
}

/// The 1-based mode `number` of the run, or an error giving the range.
pub fn mode(run: &Run, number: usize) -> Result<&Mode, CliError> {
    let modes = &run.result.modes.modes;
    number
        .checked_sub(1)
        .and_then(|i| modes.get(i))
        .ok_or_else(|| {
            CliError::usage(format!(
                "--shape {number}: no such mode (this run has modes 1 to {})",
                modes.len()
            ))
        })
}

/// The shape of mode `number` (1-based): every body drawn from its shape (point masses as
/// small cubes) and every wire, at rest and displaced, side and front views.
pub fn mode_shape(run: &Run, number: usize) -> Result<ModeShapePlot, CliError> {
    let mode = mode(run, number)?;
    let r = &run.result;
    let x = &r.assembled.equilibrium.coords;
    let mut plot = ModeShapePlot::new(format!(
        "Mode {number}: {} Hz, {} ({}): {}",
        crate::format::fixed(mode.hz, 4, 0),
        run.coord(&mode.label),
        r.mode_family(mode),
        run.heading()
    ));
    for wire in &r.system.wires {
        let [top, bottom] = wire.ends.each_ref().map(|end| {
            let at = r.system.bodies[end.body].frame.eval(x).point(&end.point);
            let (moved, _) = point_motion(run, end.body, &end.point, mode);
            (at, moved)
        });
        plot.wires.push(WireSegment {
            top: top.0.into(),
            bottom: bottom.0.into(),
            top_displacement: top.1,
            bottom_displacement: bottom.1,
        });
    }
    // point masses are drawn as cubes of 1.5 % of the suspension's height (at least 5 mm)
    let heights: Vec<f64> = plot
        .wires
        .iter()
        .flat_map(|w| [w.top[2], w.bottom[2]])
        .chain((0..r.system.bodies.len()).filter_map(|b| Some(r.body_centre(b)?.z)))
        .collect();
    let extent = heights.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        - heights.iter().copied().fold(f64::INFINITY, f64::min);
    let dot = (0.015 * extent).max(0.005);
    for (b, body) in r.system.bodies.iter().enumerate() {
        let solid = match body.shape {
            Some(Shape::Box { half_sizes }) => Solid::Box {
                half_sizes: half_sizes.into(),
            },
            Some(Shape::Cylinder {
                radius,
                half_length,
                axis,
            }) => Solid::Cylinder {
                radius,
                half_length,
                axis: [BodyAxis::X, BodyAxis::Y, BodyAxis::Z][axis.min(2)],
            },
            None if body.mass > 0.0 => Solid::Box {
                half_sizes: [dot; 3],
            },
            None => continue,
        };
        let frame = body.frame.eval(x);
        let rotation = frame.rotation;
        let (translation, turn) = point_motion(run, b, &Vector3::zeros(), mode);
        let mut outline = BodyOutline::new(run.body(&body.name), frame.origin.into(), solid);
        outline.orientation = Orientation::Matrix(std::array::from_fn(|i| {
            std::array::from_fn(|j| rotation[(i, j)])
        }));
        outline.translation = translation;
        outline.rotation = turn;
        plot.bodies.push(outline);
    }
    Ok(plot)
}

/// Writes a figure to `path` (SVG or PNG by the extension), whole or not at all, replacing
/// an existing file: every command's figures go through here. A failed write reads as any
/// other output file's (`cannot write 'PATH': reason`).
pub fn save(figure: &impl pendkit_plot::Figure, path: &std::path::Path) -> Result<(), CliError> {
    crate::output::clean_up_on_interrupt();
    figure.render(path).map_err(|e| match e {
        pendkit_plot::PlotError::Io { path, source } => CliError::Write { path, source },
        other => CliError::Plot(other),
    })
}
