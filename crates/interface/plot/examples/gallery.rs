//! Renders one of every figure, from synthetic data, as SVG and PNG into a directory:
//!
//!     cargo run -p pendkit-plot --example gallery -- OUT_DIR
//!
//! The data are made up for the pictures (textbook single-pendulum responses, a quad-like
//! geometry); they are not pendkit results.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use pendkit_plot::{
    Axis, BodePlot, BodeSeries, BodyAxis, BodyOutline, Contribution, Figure, LinePlot, ModeChart,
    ModeMarker, ModeShapePlot, NoiseBudget, PlotError, Scale, Series, Solid, TradeoffChart,
    TradeoffPoint, WireSegment,
};

/// Log-spaced frequencies (Hz).
fn logspace(from: f64, to: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| from * (to / from).powf(i as f64 / (n - 1) as f64))
        .collect()
}

/// Complex product.
fn mul(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0)
}

/// One pendulum stage with structural damping: w0²(1 + iφ) / (w0²(1 + iφ) - w²).
fn stage(f: f64, f0: f64, phi: f64) -> (f64, f64) {
    let (w, w0) = (2.0 * PI * f, 2.0 * PI * f0);
    let num = (w0 * w0, w0 * w0 * phi);
    let den = (w0 * w0 - w * w, w0 * w0 * phi);
    let d = den.0 * den.0 + den.1 * den.1;
    (
        (num.0 * den.0 + num.1 * den.1) / d,
        (num.1 * den.0 - num.0 * den.1) / d,
    )
}

fn save(figure: &impl Figure, dir: &std::path::Path, name: &str) -> Result<(), PlotError> {
    for extension in ["svg", "png"] {
        let path = dir.join(format!("{name}.{extension}"));
        figure.render(&path)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "gallery".to_string()),
    );
    std::fs::create_dir_all(&dir)?;
    let f = logspace(0.1, 100.0, 600);

    bode_figure(&dir, &f)?;
    noise_figure(&dir, &f)?;
    modes_figure(&dir)?;
    mode_shape_figure(&dir)?;
    tradeoff_figure(&dir)?;
    sweep_figure(&dir)?;
    Ok(())
}

/// A Bode plot: one pendulum stage against four, on `f`.
fn bode_figure(dir: &Path, f: &[f64]) -> Result<(), PlotError> {
    let mut bode = BodePlot::new("Support to test mass (synthetic)", "|x3/x00|", "m/m");
    let one: Vec<_> = f.iter().map(|&f| stage(f, 0.7, 1e-2)).collect();
    let four: Vec<_> = f
        .iter()
        .map(|&f| {
            [0.43, 1.0, 2.1, 3.4]
                .iter()
                .fold((1.0, 0.0), |acc, &f0| mul(acc, stage(f, f0, 1e-2)))
        })
        .collect();
    bode.series
        .push(BodeSeries::new("one stage", f.to_vec(), one));
    bode.series
        .push(BodeSeries::new("four stages", f.to_vec(), four));
    save(&bode, dir, "bode")?;
    Ok(())
}

/// A noise budget: six damping tags' shares and their total, on `f`.
fn noise_figure(dir: &Path, f: &[f64]) -> Result<(), PlotError> {
    let tags = [
        ("fibre_stretch", 1.0e-19, 4.0),
        ("fibre_bending", 3.0e-19, 2.0),
        ("fibre_torsion", 2.0e-21, 1.0),
        ("wn_bending", 5.0e-20, 6.0),
        ("w1_bending", 2.0e-20, 8.0),
        ("blade_1", 8.0e-21, 10.0),
    ];
    let parts: Vec<Contribution> = tags
        .iter()
        .map(|&(name, level, slope)| {
            let asd = f
                .iter()
                .map(|&f| {
                    let resonance = stage(f, 0.6 + slope / 10.0, 1e-3);
                    level * resonance.0.hypot(resonance.1) * (1.0 / f).powf(slope / 4.0)
                })
                .collect();
            Contribution::new(name, asd)
        })
        .collect();
    let total = (0..f.len())
        .map(|i| {
            parts
                .iter()
                .map(|p| p.asd[i] * p.asd[i])
                .sum::<f64>()
                .sqrt()
        })
        .collect();
    let mut budget = NoiseBudget::new(
        "Test-mass thermal noise (synthetic)",
        "displacement ASD",
        "m/√Hz",
        f.to_vec(),
        Contribution::new("total", total),
    );
    budget.contributions = parts;
    save(&budget, dir, "noise")?;
    Ok(())
}

/// A mode chart: four modes per degree of freedom, violin modes and one growing mode.
fn modes_figure(dir: &Path) -> Result<(), PlotError> {
    let mut modes: Vec<ModeMarker> = [
        (0.43, "L"),
        (0.99, "L"),
        (2.0, "L"),
        (3.4, "L"),
        (0.44, "T"),
        (1.0, "T"),
        (1.9, "T"),
        (3.5, "T"),
        (0.56, "P"),
        (1.0, "P"),
        (2.6, "P"),
        (3.8, "P"),
        (0.61, "Y"),
        (1.1, "Y"),
        (2.4, "Y"),
        (3.6, "Y"),
        (1.3, "R"),
        (4.9, "R"),
        (13.9, "R"),
        (27.0, "R"),
        (1.9, "V"),
        (6.9, "V"),
        (9.6, "V"),
        (16.0, "V"),
        (497.0, "violin"),
        (502.0, "violin"),
        (505.0, "violin"),
        (991.0, "violin"),
    ]
    .iter()
    .map(|&(f, family)| ModeMarker::new(f, family))
    .collect();
    modes.push(ModeMarker {
        frequency_hz: -0.05,
        family: "Y".to_string(),
        label: Some("growth 0.05".to_string()),
        unstable: true,
    });
    save(
        &ModeChart::new("Modes by degree of freedom (synthetic)", modes),
        dir,
        "modes",
    )?;
    Ok(())
}

/// A mode shape: a quad-like chain of four bodies, displaced, and the wires between them.
fn mode_shape_figure(dir: &Path) -> Result<(), PlotError> {
    let mut shape = ModeShapePlot::new("Mode 9: 1.0 Hz, P (synthetic quad-like geometry)");
    let stages = [
        (
            "M0",
            0.0,
            Solid::Box {
                half_sizes: [0.16, 0.25, 0.05],
            },
            [0.0, 0.0, 0.0],
            0.0,
        ),
        (
            "L1",
            -0.45,
            Solid::Box {
                half_sizes: [0.15, 0.2, 0.05],
            },
            [1e-4, 0.0, 0.0],
            2e-4,
        ),
        (
            "L2",
            -0.85,
            Solid::Cylinder {
                radius: 0.17,
                half_length: 0.1,
                axis: BodyAxis::X,
            },
            [3e-4, 0.0, 0.0],
            -1e-3,
        ),
        (
            "L3",
            -1.5,
            Solid::Cylinder {
                radius: 0.17,
                half_length: 0.1,
                axis: BodyAxis::X,
            },
            [-2e-4, 0.0, 0.0],
            1.5e-3,
        ),
    ];
    let mut previous: Option<([f64; 3], [f64; 3], f64)> = None;
    for (name, z, solid, translation, pitch) in stages {
        let mut body = BodyOutline::new(name, [0.0, 0.0, z], solid);
        body.translation = translation;
        body.rotation = [0.0, pitch, 0.0];
        shape.bodies.push(body);
        let top_z = z + 0.1;
        if let Some((above_centre, above_translation, above_pitch)) = previous {
            for side in [-0.15, 0.15] {
                let top = [0.0, side, above_centre[2] - 0.1];
                let bottom = [0.0, side, top_z];
                // Point displacements of a body: translation + rotation × arm.
                let moved = |t: [f64; 3], p: f64, arm_z: f64| [t[0] + p * arm_z, t[1], t[2]];
                shape.wires.push(WireSegment {
                    top,
                    bottom,
                    top_displacement: moved(above_translation, above_pitch, -0.1),
                    bottom_displacement: moved(translation, pitch, 0.1),
                });
            }
        }
        previous = Some(([0.0, 0.0, z], translation, pitch));
    }
    save(&shape, dir, "mode_shape")?;
    Ok(())
}

/// A trade-off chart: run time against error for a ladder of variants.
fn tradeoff_figure(dir: &Path) -> Result<(), PlotError> {
    let variants = [
        ("stage 0A", 0.0009, 0.2),
        ("stage 1A", 0.0012, 0.03),
        ("stage 2, lite", 0.0021, 0.004),
        ("stage 2", 0.0035, 8e-4),
        ("beads 1", 0.0051, 2e-4),
        ("beads 5", 0.012, 3e-4),
        ("beads 10", 0.04, 1e-5),
        ("beads 20", 0.11, 2e-6),
        ("full solve", 0.015, 8e-4),
        ("beads 40 (reference)", 0.45, 0.0),
    ];
    let points = variants
        .iter()
        .map(|&(name, s, e)| TradeoffPoint::new(name, s, e))
        .collect();
    let mut tradeoff = TradeoffChart::new("Speed against accuracy (synthetic)", points);
    tradeoff.tolerance = Some(1e-3);
    save(&tradeoff, dir, "tradeoff")?;
    Ok(())
}

/// A parameter sweep: two frequencies against fibre radius.
fn sweep_figure(dir: &Path) -> Result<(), PlotError> {
    let radius: Vec<f64> = (0..30).map(|i| 0.1e-3 + 0.02e-3 * i as f64).collect();
    let mut sweep = LinePlot::new(
        "Violin and bounce frequencies against fibre radius (synthetic)",
        Axis::new("fibre radius", "m", Scale::Linear),
        Axis::new("frequency", "Hz", Scale::Log),
    );
    sweep.markers = true;
    sweep.series.push(Series::new(
        "first violin mode",
        radius.clone(),
        radius.iter().map(|r| 500.0 * (r / 0.2e-3)).collect(),
    ));
    sweep.series.push(Series::new(
        "bounce",
        radius.clone(),
        radius.iter().map(|r| 9.0 * (r / 0.2e-3)).collect(),
    ));
    save(&sweep, dir, "sweep")?;
    Ok(())
}
