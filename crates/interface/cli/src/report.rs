//! `pendkit report`: one self-contained HTML page about a model or case: its parameters
//! with units, stages and element kinds, equilibrium, stability verdict, modes (table,
//! chart, shapes), the standard transfer functions, the thermal-noise budget, and how long
//! each phase took. Figures are inline SVG; the page loads nothing (no scripts, no fonts,
//! no network), so it opens anywhere and can be archived as one file.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use pendkit::energy::registrations;

use pendkit::Solver;
use pendkit::stage::ModeSelection;
use pendkit::system::{CoordKind, Shape, Stage};
use pendkit_plot::Figure;

use crate::common::{GridArgs, ModelArgs, Run};
use crate::error::CliError;
use crate::format::{fixed, sci};
use crate::output::{OutputDir, write_file};
use crate::plotting::{self, Response};
use crate::progress::Progress;

// Arguments of `pendkit report` (a plain comment: see `Command` on why clap must not read it).
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    args: ModelArgs,
    /// Directory to write the report to (created if needed): DIR/index.html.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    #[command(flatten)]
    grid: GridArgs,
    /// Number of mode shapes drawn: the lowest mode of each family first, up to N.
    #[arg(long, default_value_t = 6, value_name = "N")]
    shapes: usize,
}

/// Text made safe for HTML.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The page under construction, with the report's own phase times.
struct Page {
    html: String,
    figures: usize,
    times: Vec<(String, f64)>,
}

impl Page {
    fn section(&mut self, id: &str, title: &str) {
        let _ = writeln!(self.html, "<section id=\"{id}\"><h2>{}</h2>", escape(title));
    }

    fn end_section(&mut self) {
        self.html.push_str("</section>\n");
    }

    fn paragraph(&mut self, text: &str) {
        let _ = writeln!(self.html, "<p>{}</p>", escape(text));
    }

    /// A table: header cells and rows of cells (already text; escaped here).
    fn table(&mut self, header: &[&str], rows: &[Vec<String>]) {
        self.html.push_str("<table><thead><tr>");
        for h in header {
            let _ = write!(self.html, "<th>{}</th>", escape(h));
        }
        self.html.push_str("</tr></thead><tbody>\n");
        for row in rows {
            self.html.push_str("<tr>");
            for cell in row {
                let _ = write!(self.html, "<td>{}</td>", escape(cell));
            }
            self.html.push_str("</tr>\n");
        }
        self.html.push_str("</tbody></table>\n");
    }

    /// An inline SVG figure with a caption.
    fn figure(&mut self, figure: &impl Figure, caption: &str) -> Result<(), CliError> {
        let svg = figure.to_svg()?;
        self.figures += 1;
        let _ = writeln!(
            self.html,
            "<figure id=\"figure-{}\">{svg}<figcaption>{}</figcaption></figure>",
            self.figures,
            escape(caption)
        );
        Ok(())
    }

    /// Runs `f`, recording its time as report phase `name`.
    fn timed<T>(&mut self, name: &str, f: impl FnOnce(&mut Page) -> T) -> T {
        let start = Instant::now();
        let out = f(self);
        self.times
            .push((name.to_string(), start.elapsed().as_secs_f64()));
        out
    }
}

const STYLE: &str = "body{font-family:'DejaVu Sans',Verdana,sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}\
h1{font-size:1.6em}h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:2em}\
table{border-collapse:collapse;margin:1em 0;font-size:.9em}th,td{border:1px solid #ddd;padding:.25em .6em;text-align:left}\
th{background:#f3f3f3}td{font-variant-numeric:tabular-nums}figure{margin:1.5em 0}figure svg{max-width:100%;height:auto;display:block}\
figcaption{font-size:.9em;color:#555}.verdict{font-weight:bold;padding:.5em 1em;display:inline-block}\
.stable{background:#e6f4e6;color:#1a5e1a}.unstable{background:#fbe4e4;color:#8a1c1c}\
.neutral{background:#fdf3d8;color:#6b4e00}nav a{margin-right:1em}";

/// Runs the command and returns what it prints.
pub fn run(a: Args) -> Result<String, CliError> {
    let progress = Progress::new(Some(7), "report: run");
    let started = Instant::now();
    let run = a.args.run(ModeSelection::All)?;
    progress.step();
    let freqs = a.grid.frequencies()?;
    let mut page = Page {
        html: String::new(),
        figures: 0,
        times: Vec::new(),
    };
    let title = format!("pendkit report: {}", run.heading());
    let _ = writeln!(
        page.html,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title><style>{STYLE}</style></head><body>",
        escape(&title)
    );
    let _ = writeln!(page.html, "<h1>{}</h1>", escape(&title));
    page.html.push_str(
        "<nav><a href=\"#model\">Model</a><a href=\"#equilibrium\">Equilibrium</a><a href=\"#stability\">Stability</a><a href=\"#modes\">Modes</a><a href=\"#transfer\">Transfer functions</a><a href=\"#noise\">Thermal noise</a><a href=\"#timing\">Timing</a></nav>\n",
    );
    progress.message("report: model");
    page.timed("report:model", |p| model_section(p, &run))?;
    progress.step();
    equilibrium_section(&mut page, &run);
    // an unstable equilibrium gets its verdict and modes; the responses of its
    // linearisation only with --allow-unstable (the warning on stderr, as for `tf`)
    let stable = stability_section(&mut page, &run, a.args.allow_unstable);
    if !stable && a.args.allow_unstable {
        run.check_stable(true)?; // the warning on stderr
    }
    let answer = lossy_answer(&run) && (stable || a.args.allow_unstable);
    progress.message("report: modes");
    page.timed("report:modes", |p| modes_section(p, &run, a.shapes))?;
    progress.step();
    progress.message("report: transfer functions");
    page.timed("report:transfer-functions", |p| {
        transfer_section(p, &run, &freqs, answer)
    })?;
    progress.step();
    progress.message("report: thermal noise");
    page.timed("report:noise", |p| noise_section(p, &run, &freqs, answer))?;
    progress.step();
    timing_section(&mut page, &run, started.elapsed().as_secs_f64());
    let _ = writeln!(
        page.html,
        "<footer><p>pendkit {} &middot; {} frequencies from {} to {} Hz</p></footer></body></html>",
        pendkit::VERSION,
        freqs.len(),
        freqs.first().copied().unwrap_or_default(),
        freqs.last().copied().unwrap_or_default()
    );
    progress.message("report: write");
    let dir = OutputDir::create(&a.out)?;
    let path = dir.join("index.html");
    write_file(&path, page.html.as_bytes())?;
    dir.keep();
    progress.step();
    drop(progress);
    let mut out = format!(
        "{}: wrote {} ({} figures, {} kB)",
        run.heading(),
        path.display(),
        page.figures,
        page.html.len() / 1000
    );
    if !stable {
        out.push_str("; the equilibrium is unstable (see the report's stability verdict)");
    }
    out.push('\n');
    Ok(out)
}

fn model_section(page: &mut Page, run: &Run) -> Result<(), CliError> {
    let r = &run.result;
    page.section("model", "Model");
    page.paragraph(&format!(
        "{}: {}",
        run.case.model.name(),
        run.case.model.summary()
    ));
    if let Some(d) = &run.case.description {
        page.paragraph(&format!("Case {}: {d}", run.case.name));
    }
    let count = |k: CoordKind| r.system.coords.iter().filter(|c| c.kind == k).count();
    page.paragraph(&format!(
        "{} bodies, {} wires, {} springs; {} variables, {} floats, {} parameters (driven coordinates); temperature {} K; stage {} computed.",
        r.system.bodies.len(),
        r.system.wires.len(),
        r.system.springs.len(),
        count(CoordKind::Variable),
        count(CoordKind::Float),
        count(CoordKind::Parameter),
        r.system.temperature,
        run.stage
    ));
    let provenance = run.provenance()?;
    let _ = writeln!(page.html, "<h3>Parameters</h3>");
    let rows: Vec<Vec<String>> = provenance
        .parameters
        .iter()
        .map(|p| {
            vec![
                p.name.clone(),
                sci(p.value, 6, 0),
                p.unit.clone().unwrap_or_else(|| "(not declared)".into()),
                format!(
                    "{}{}",
                    p.definition,
                    if p.overridden { " (overridden)" } else { "" }
                ),
            ]
        })
        .collect();
    page.table(&["name", "value", "unit", "definition"], &rows);
    bodies_table(page, run);
    stages_tables(page, run);
    damping_table(page, run);
    page.end_section();
    Ok(())
}

/// The bodies with mass: mass, principal inertias, centre at equilibrium, and the shape
/// they are drawn as.
fn bodies_table(page: &mut Page, run: &Run) {
    let r = &run.result;
    let _ = writeln!(page.html, "<h3>Bodies</h3>");
    let rows: Vec<Vec<String>> = r
        .system
        .bodies
        .iter()
        .enumerate()
        .filter(|(_, b)| b.mass > 0.0)
        .map(|(k, b)| {
            let i = b.inertia;
            // every body of the model has a centre
            let centre = r.body_centre(k).unwrap_or_default();
            vec![
                run.body(&b.name),
                fixed(b.mass, 4, 0),
                format!(
                    "{} {} {}",
                    sci(i[(0, 0)], 4, 0),
                    sci(i[(1, 1)], 4, 0),
                    sci(i[(2, 2)], 4, 0)
                ),
                format!(
                    "{} {} {}",
                    fixed(centre.x, 4, 0),
                    fixed(centre.y, 4, 0),
                    fixed(centre.z, 4, 0)
                ),
                match b.shape {
                    Some(Shape::Box { half_sizes: h }) => format!(
                        "box {} x {} x {} m",
                        fixed(2.0 * h.x, 3, 0),
                        fixed(2.0 * h.y, 3, 0),
                        fixed(2.0 * h.z, 3, 0)
                    ),
                    Some(Shape::Cylinder {
                        radius,
                        half_length,
                        axis,
                    }) => format!(
                        "cylinder r = {} m, h = {} m along {}",
                        fixed(radius, 3, 0),
                        fixed(2.0 * half_length, 3, 0),
                        ["x", "y", "z"][axis.min(2)]
                    ),
                    None => "point mass".into(),
                },
            ]
        })
        .collect();
    page.table(
        &[
            "body",
            "mass (kg)",
            "principal inertias x y z (kg m^2)",
            "centre at equilibrium x y z (m)",
            "drawn as",
        ],
        &rows,
    );
}

/// What each stage adds (and which this report computed), and every registered element
/// kind with the stage it joins at.
fn stages_tables(page: &mut Page, run: &Run) {
    let _ = writeln!(page.html, "<h3>Stages and element kinds</h3>");
    let stage_rows: Vec<Vec<String>> = [
        (
            Stage::S0A,
            "gravity, springs, wire stretch; equilibrium, modes",
        ),
        (
            Stage::S0B,
            "dissipation dilution: every term with tension on and off",
        ),
        (Stage::S1A, "wire torsion"),
        (Stage::S1B, "wire bending (lossy)"),
        (
            Stage::S2,
            "wire extra stretch (work against tension, lossless)",
        ),
    ]
    .iter()
    .map(|(s, what)| {
        vec![
            s.name().to_string(),
            what.to_string(),
            if *s == run.stage {
                "computed here".into()
            } else if *s < run.stage {
                "included".into()
            } else {
                String::new()
            },
        ]
    })
    .collect();
    page.table(&["stage", "adds", "this report"], &stage_rows);
    let kinds: Vec<Vec<String>> = registrations()
        .iter()
        .map(|reg| {
            vec![
                reg.element.kind().to_string(),
                reg.element.stage().name().to_string(),
                reg.crate_name.to_string(),
                reg.element.summary().to_string(),
            ]
        })
        .collect();
    page.table(&["element kind", "joins at", "crate", "what"], &kinds);
}

/// Each damping tag's multiplier at 1 Hz and 10 Hz.
fn damping_table(page: &mut Page, run: &Run) {
    let r = &run.result;
    let _ = writeln!(page.html, "<h3>Damping</h3>");
    let tags: Vec<Vec<String>> = r
        .system
        .damping
        .tags()
        .map(|tag| {
            let (re, im) = r.system.damping.at(tag, 1.0);
            let (re10, im10) = r.system.damping.at(tag, 10.0);
            vec![
                tag.to_string(),
                format!("{} + {}i", fixed(re, 3, 0), sci(im, 3, 0)),
                format!("{} + {}i", fixed(re10, 3, 0), sci(im10, 3, 0)),
            ]
        })
        .collect();
    page.table(
        &["damping tag", "multiplier at 1 Hz", "multiplier at 10 Hz"],
        &tags,
    );
}

fn equilibrium_section(page: &mut Page, run: &Run) {
    let r = &run.result;
    let eq = &r.assembled.equilibrium;
    page.section("equilibrium", "Equilibrium");
    page.paragraph(&format!(
        "Found in {} Newton steps; largest residual force {} (N or N m).",
        eq.iterations,
        sci(eq.max_residual, 2, 0)
    ));
    let rows: Vec<Vec<String>> = r
        .system
        .coords
        .iter()
        .zip(&eq.coords)
        .filter(|(c, _)| c.kind != CoordKind::Parameter)
        .map(|(c, x)| {
            vec![
                run.coord(&c.name),
                match c.kind {
                    CoordKind::Variable => "variable".into(),
                    _ => "float".into(),
                },
                sci(*x, 6, 0),
                r.coordinate_unit(&c.name).unwrap_or("").to_string(),
            ]
        })
        .collect();
    page.table(&["coordinate", "kind", "value", "unit"], &rows);
    page.end_section();
}

/// Whether the stage has losses for transfer functions and noise: from stage 0B on (no
/// dissipation dilution at 0A).
fn lossy_answer(run: &Run) -> bool {
    run.stage != Stage::S0A
}

/// Writes the verdict and returns whether the equilibrium is stable.
fn stability_section(page: &mut Page, run: &Run, allow_unstable: bool) -> bool {
    page.section("stability", "Stability");
    let verdict = run.result.stability();
    let stable = verdict.is_ok();
    let neutral = run.neutral_notes();
    let text = match verdict {
        Ok(()) if !neutral.is_empty() => format!(
            "Neutral: every mode has ω² ≥ 0, but {} {} zero (a neutral direction: nothing resists it, and a steady force along it has no finite response).",
            neutral.len(),
            if neutral.len() == 1 {
                "mode's is"
            } else {
                "modes' are"
            }
        ),
        Ok(()) => "Stable: every mode has ω² ≥ 0.".to_string(),
        Err(e) if allow_unstable => format!(
            "Unstable: {e}. Transfer functions and noise below are those of the linearisation (--allow-unstable)."
        ),
        Err(e) => format!(
            "Unstable: {e}. Transfer functions and noise are not computed (--allow-unstable computes those of the linearisation)."
        ),
    };
    let class = match (stable, neutral.is_empty()) {
        (false, _) => "unstable",
        (true, false) => "neutral",
        (true, true) => "stable",
    };
    let _ = writeln!(
        page.html,
        "<p class=\"verdict {class}\">{}</p>",
        escape(&text)
    );
    // each neutral direction with what moves in it and how to remove it, here and on
    // stderr beside the file written (as `modes` prints them beside its table)
    for note in &neutral {
        let _ = writeln!(page.html, "<p>{}</p>", escape(note));
        eprintln!("{note}");
    }
    page.end_section();
    stable
}

fn modes_section(page: &mut Page, run: &Run, shapes: usize) -> Result<(), CliError> {
    let r = &run.result;
    page.section("modes", "Normal modes");
    page.figure(
        &plotting::mode_chart(run),
        "Mode frequencies by degree-of-freedom family (L longitudinal, T transverse, V vertical, R roll, P pitch, Y yaw).",
    )?;
    let rows: Vec<Vec<String>> = r
        .modes
        .modes
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let top = crate::modes::top_shares(run, &r.modes.coordinates, &m.energy_fractions);
            vec![
                (i + 1).to_string(),
                fixed(m.hz, 6, 0),
                r.mode_family(m),
                run.coord(&m.label),
                top.join(", "),
            ]
        })
        .collect();
    page.table(
        &[
            "mode",
            "frequency (Hz)",
            "family",
            "label",
            "kinetic energy share",
        ],
        &rows,
    );
    // the lowest mode of each family first, then the next lowest modes, up to `shapes`
    let mut chosen: Vec<usize> = Vec::new();
    let mut families: Vec<String> = Vec::new();
    for (i, m) in r.modes.modes.iter().enumerate() {
        let family = r.mode_family(m);
        if !families.contains(&family) {
            families.push(family);
            chosen.push(i);
        }
    }
    chosen.truncate(shapes);
    for i in 0..r.modes.modes.len() {
        if chosen.len() >= shapes {
            break;
        }
        if !chosen.contains(&i) {
            chosen.push(i);
        }
    }
    chosen.sort_unstable();
    for i in chosen {
        page.figure(
            &plotting::mode_shape(run, i + 1)?,
            &format!(
                "Shape of mode {}: side and front views, at rest (light) and displaced (dark).",
                i + 1
            ),
        )?;
    }
    page.end_section();
    Ok(())
}

fn transfer_section(
    page: &mut Page,
    run: &Run,
    freqs: &[f64],
    compute: bool,
) -> Result<(), CliError> {
    let r = &run.result;
    page.section("transfer", "Transfer functions");
    if !compute {
        page.paragraph(
            "Not computed: they need a stable equilibrium (or --allow-unstable) and stage 0B or later (no dissipation dilution at 0A).",
        );
        page.end_section();
        return Ok(());
    }
    let pairs = r.standard_transfer_functions();
    if pairs.is_empty() {
        page.paragraph("This model has no body with mass to be the test mass.");
        page.end_section();
        return Ok(());
    }
    let tm = r
        .test_mass()
        .map(|b| run.body(&r.system.bodies[b].name))
        .unwrap_or_default();
    page.paragraph(&format!(
        "From the support's displacement and from a force or torque on the test mass ({tm}: the lowest body with the most degrees of freedom) to the test mass's displacement, in each degree of freedom."
    ));
    let mut responses: Vec<(String, Response)> = Vec::new();
    for (input, output) in &pairs {
        // the stability section above decided whether to answer at all
        let values = r.transfer_with(input, output, freqs, Solver::Restricted)?;
        let unit = r.transfer_unit(input, output).unwrap_or_default();
        let kind = if input.starts_with("force:") {
            "force"
        } else {
            "support"
        };
        responses.push((
            kind.to_string(),
            Response {
                name: format!("{}/{}", run.port(output), run.port(input)),
                unit,
                values,
            },
        ));
    }
    bode_figures(page, run, freqs, &responses)?;
    magnitude_table(page, freqs, &responses);
    page.end_section();
    Ok(())
}

/// The Bode plots of `responses` (input kind, response), one per input kind and unit;
/// the responses that are zero at every frequency listed instead.
fn bode_figures(
    page: &mut Page,
    run: &Run,
    freqs: &[f64],
    responses: &[(String, Response)],
) -> Result<(), CliError> {
    // one Bode plot per input kind and unit
    let mut groups: Vec<(String, String)> = Vec::new();
    for (kind, resp) in responses {
        if !groups.contains(&(kind.clone(), resp.unit.clone())) {
            groups.push((kind.clone(), resp.unit.clone()));
        }
    }
    // identically zero responses (a degree of freedom the input does not reach) have no
    // place on log axes: they are listed instead of drawn
    let zero: Vec<String> = responses
        .iter()
        .filter(|(_, resp)| resp.values.iter().all(|h| h.norm() == 0.0))
        .map(|(_, resp)| resp.name.clone())
        .collect();
    if !zero.is_empty() {
        page.paragraph(&format!(
            "Zero at every frequency, so not drawn: {}.",
            zero.join(", ")
        ));
    }
    for (kind, unit) in &groups {
        let list: Vec<Response> = responses
            .iter()
            .filter(|(k, resp)| k == kind && resp.unit == *unit)
            .filter(|(_, resp)| !zero.contains(&resp.name))
            .map(|(_, resp)| Response {
                name: resp.name.clone(),
                unit: resp.unit.clone(),
                values: resp.values.clone(),
            })
            .collect();
        if list.is_empty() {
            continue;
        }
        let title = if kind == "support" {
            format!("Support to test mass ({unit}): {}", run.heading())
        } else {
            format!("Force to test mass ({unit}): {}", run.heading())
        };
        let plot = plotting::bode(&title, freqs, &list)?;
        page.figure(&plot, &title)?;
    }
    Ok(())
}

/// |H| of each of `responses` at the grid frequencies nearest 1, 10 and 100 Hz.
fn magnitude_table(page: &mut Page, freqs: &[f64], responses: &[(String, Response)]) {
    // magnitudes at a few frequencies of the grid
    let picks: Vec<usize> = [1.0, 10.0, 100.0]
        .iter()
        .filter_map(|target: &f64| {
            (0..freqs.len()).min_by(|&i, &j| {
                (freqs[i].ln() - target.ln())
                    .abs()
                    .total_cmp(&(freqs[j].ln() - target.ln()).abs())
            })
        })
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect();
    let mut header: Vec<String> = vec!["transfer function".into(), "unit".into()];
    header.extend(
        picks
            .iter()
            .map(|&i| format!("|H| at {} Hz", sci(freqs[i], 3, 0))),
    );
    let rows: Vec<Vec<String>> = responses
        .iter()
        .map(|(_, resp)| {
            let mut row = vec![resp.name.clone(), resp.unit.clone()];
            row.extend(picks.iter().map(|&i| sci(resp.values[i].norm(), 4, 0)));
            row
        })
        .collect();
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    page.table(&header, &rows);
}

fn noise_section(page: &mut Page, run: &Run, freqs: &[f64], compute: bool) -> Result<(), CliError> {
    let r = &run.result;
    page.section("noise", "Thermal noise");
    if !compute {
        page.paragraph(
            "Not computed: it needs a stable equilibrium (or --allow-unstable) and stage 0B or later (no dissipation dilution at 0A).",
        );
        page.end_section();
        return Ok(());
    }
    let Some(output) = r
        .standard_transfer_functions()
        .into_iter()
        .next()
        .map(|(_, o)| o)
    else {
        page.paragraph("This model has no body with mass to be the test mass.");
        page.end_section();
        return Ok(());
    };
    let noise = plotting::noise(run, &output, freqs)?;
    if noise.psd().iter().any(|&p| p > 0.0) {
        page.figure(
            &plotting::noise_budget(run, &output, freqs, &noise),
            &format!(
                "Thermal noise of the test mass's {} by the fluctuation-dissipation theorem: the total and each damping tag's share (ASD; the shares add in power).",
                run.port(&output)
            ),
        )?;
    } else {
        // a log-log plot of zeros is empty: say why there is no figure instead
        page.paragraph(&format!(
            "The thermal noise of the test mass's {} is zero at every frequency: no lossy term couples to it (for example, only wire-stretch loss, which dilution removes from horizontal motion).",
            run.port(&output)
        ));
    }
    let unit = format!("{}/√Hz", r.output_unit(&output).unwrap_or_default());
    let at = (0..freqs.len())
        .min_by(|&i, &j| {
            (freqs[i].ln() - 10f64.ln())
                .abs()
                .total_cmp(&(freqs[j].ln() - 10f64.ln()).abs())
        })
        .unwrap_or(0);
    let psd = noise.psd();
    let mut rows: Vec<Vec<String>> = noise
        .psd_by_tag()
        .iter()
        .map(|(tag, series)| {
            vec![
                tag.clone(),
                sci(series[at].max(0.0).sqrt(), 4, 0),
                format!(
                    "{}%",
                    fixed(100.0 * series[at] / psd[at].max(f64::MIN_POSITIVE), 1, 0)
                ),
            ]
        })
        .collect();
    rows.sort_by(|a, b| {
        let share = |r: &Vec<String>| r[1].parse::<f64>().unwrap_or(0.0);
        share(b).total_cmp(&share(a))
    });
    rows.insert(
        0,
        vec![
            "total".into(),
            sci(psd[at].max(0.0).sqrt(), 4, 0),
            "100%".into(),
        ],
    );
    let header = format!("ASD at {} Hz ({unit})", sci(freqs[at], 3, 0));
    page.table(&["damping tag", &header, "share of the PSD"], &rows);
    page.end_section();
    Ok(())
}

fn timing_section(page: &mut Page, run: &Run, total: f64) {
    page.section("timing", "Timing");
    page.paragraph(
        "Wall-clock time of each phase of this report (one run, in this process; the build and the stage's phases as `pendkit bench` names them).",
    );
    let mut rows: Vec<Vec<String>> = run
        .times
        .phases()
        .iter()
        .map(|p| {
            vec![
                p.name.clone(),
                fixed(1e3 * p.seconds, 3, 0),
                p.calls.to_string(),
            ]
        })
        .collect();
    rows.extend(
        page.times
            .iter()
            .map(|(name, s)| vec![name.clone(), fixed(1e3 * s, 3, 0), "1".into()]),
    );
    rows.push(vec![
        "total".into(),
        fixed(1e3 * total, 3, 0),
        String::new(),
    ]);
    page.table(&["phase", "time (ms)", "calls"], &rows);
    page.end_section();
}
