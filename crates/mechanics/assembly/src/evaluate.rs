//! Evaluation of many terms at one configuration, sharing the work: every body's frame jet
//! is computed once and read by all terms touching the body; terms that are parts of one
//! shared energy body (a wire's beam: bending and extra stretch) are evaluated together
//! once; the tension-on and tension-off Hessians come from the same pass; and results at
//! the current configuration are kept, so the equilibrium search hands its last
//! evaluation to the assembly instead of repeating it. Buffers are reused, so repeated
//! evaluations do not allocate (except on the reference path).

use std::collections::HashMap;
use std::time::{Duration, Instant};

use pendkit_energy::{
    Derivatives, FrameAt, JetPoint, LocalDerivatives, OffForm, OffHessian, PartOff, Scratch,
    TensionOff, Term, on_stack,
};

use pendkit_geometry::{FrameJet, JetOrder};
use pendkit_system::System;

/// How terms are differentiated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DerivativePath {
    /// Each term's fast path when it has one (shared frame jets, chain rule), else the
    /// reference path.
    #[default]
    Fast,
    /// Hyper-dual numbers over every term's energy body, one evaluation per Hessian entry
    /// (the reference the fast path is checked against).
    Reference,
}

/// How much of a group is known at the current configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Level {
    Nothing,
    Gradient,
    Hessians,
}

/// Terms evaluated together: one energy body (its own, or a shared one and the terms of
/// its parts), with its slice of the flat result buffers.
#[derive(Debug)]
struct Group {
    /// Term indices and the part each is.
    members: Members,
    /// Number of local coordinates.
    n: usize,
    /// Energy parts the body yields.
    parts: usize,
    /// Offsets into the value and gradient buffers.
    value_at: usize,
    gradient_at: usize,
    /// Hessians of every part with the tension on (part p at p n²), and the tension-off
    /// Hessian of a single-part body: the group's own buffers, handed over to the
    /// assembled matrices at the end.
    on: Vec<f64>,
    off: Vec<f64>,
    /// Whether the body has a fast path (known after its first evaluation).
    fast: Option<bool>,
    level: Level,
    /// Tension-off form of a single-part body, from its last Hessian evaluation.
    off_form: OffForm,
    /// The element kinds of its terms (two for a body shared by two kinds), for timing.
    kinds: [Option<&'static str>; 2],
    /// Time spent evaluating Hessians, and how many times, since the last
    /// [`Evaluator::take_times`].
    time: Duration,
    timed: usize,
}

/// The terms of a group with the part each is: one, or several for a shared body (without
/// allocating for one).
#[derive(Debug)]
struct Members {
    first: (usize, usize),
    more: Vec<(usize, usize)>,
}

impl Members {
    fn iter(&self) -> impl Iterator<Item = &(usize, usize)> {
        std::iter::once(&self.first).chain(&self.more)
    }

    fn len(&self) -> usize {
        1 + self.more.len()
    }
}

/// Evaluates a set of terms of one system, sharing frame jets and keeping results at the
/// current configuration (see the module documentation).
pub(crate) struct Evaluator<'s> {
    system: &'s System,
    path: DerivativePath,
    terms: Vec<Term>,
    groups: Vec<Group>,
    /// The groups of each shared energy body (by its address, the first value of
    /// `Term::body_parts`), so that a part finds its group without a search over all groups.
    shared_groups: HashMap<usize, Vec<usize>>,
    /// Group of each term.
    group_of: Vec<usize>,
    /// The configuration the kept results belong to.
    point: Vec<f64>,
    jets: Vec<FrameJet>,
    /// Whether each body's jet is at `point`.
    jet_ready: Vec<bool>,
    values: Vec<f64>,
    gradients: Vec<f64>,
    force_scales: Vec<f64>,
    /// Reference-path tension-off Hessians (their own allocations: the slow path).
    reference_off: Vec<Option<OffHessian>>,
    scratch: Scratch,
    local_x: Vec<f64>,
    /// Record per-group Hessian times.
    pub(crate) timing: bool,
}

impl<'s> Evaluator<'s> {
    pub(crate) fn new(system: &'s System, path: DerivativePath) -> Self {
        Evaluator {
            system,
            path,
            terms: Vec::new(),
            groups: Vec::new(),
            shared_groups: HashMap::new(),
            group_of: Vec::new(),
            point: Vec::new(),
            jets: (0..system.bodies.len()).map(|_| FrameJet::new()).collect(),
            jet_ready: vec![false; system.bodies.len()],
            values: Vec::new(),
            gradients: Vec::new(),
            force_scales: Vec::new(),
            reference_off: Vec::new(),
            scratch: Scratch::default(),
            local_x: Vec::new(),
            timing: false,
        }
    }

    /// Adds terms; a term that is a part of a body already present joins its group.
    pub(crate) fn extend(&mut self, terms: impl IntoIterator<Item = Term>) {
        for term in terms {
            let t = self.terms.len();
            let (body, parts, part) = term.body_parts();
            let n = term.coords.len();
            let joined = (parts > 1)
                .then(|| {
                    self.shared_groups.get(&body).and_then(|groups| {
                        groups.iter().copied().find(|&g| {
                            self.terms[self.groups[g].members.first.0].coords == term.coords
                        })
                    })
                })
                .flatten();
            let g = match joined {
                Some(g) => {
                    let group = &mut self.groups[g];
                    if group.kinds[0] != Some(term.kind) {
                        group.kinds[1] = Some(term.kind);
                    }
                    group.members.more.push((t, part));
                    group.level = Level::Nothing;
                    g
                }
                None => {
                    self.groups.push(Group {
                        members: Members {
                            first: (t, part),
                            more: Vec::new(),
                        },
                        n,
                        parts,
                        value_at: self.values.len(),
                        gradient_at: self.gradients.len(),
                        on: vec![0.0; parts * n * n],
                        off: if parts == 1 {
                            vec![0.0; n * n]
                        } else {
                            Vec::new()
                        },
                        fast: None,
                        level: Level::Nothing,
                        off_form: OffForm::Same,
                        kinds: [Some(term.kind), None],
                        time: Duration::ZERO,
                        timed: 0,
                    });
                    self.values.resize(self.values.len() + parts, 0.0);
                    self.gradients.resize(self.gradients.len() + parts * n, 0.0);
                    self.force_scales.resize(self.gradients.len(), 0.0);
                    let g = self.groups.len() - 1;
                    if parts > 1 {
                        self.shared_groups.entry(body).or_default().push(g);
                    }
                    g
                }
            };
            self.group_of.push(g);
            self.reference_off.push(None);
            self.terms.push(term);
        }
    }

    /// Removes the terms from index `len` on. They were added last and form whole groups
    /// (a shared body's terms are always added together), so their groups are the last
    /// ones and the indices of the groups kept do not change.
    pub(crate) fn truncate(&mut self, len: usize) {
        let first_removed = self
            .groups
            .iter()
            .position(|g| g.members.iter().any(|&(t, _)| t >= len))
            .unwrap_or(self.groups.len());
        self.groups.truncate(first_removed);
        self.shared_groups.retain(|_, groups| {
            groups.retain(|&g| g < first_removed);
            !groups.is_empty()
        });
        self.terms.truncate(len);
        self.group_of.truncate(len);
        self.reference_off.truncate(len);
    }

    pub(crate) fn path(&self) -> DerivativePath {
        self.path
    }

    pub(crate) fn terms(&self) -> &[Term] {
        &self.terms
    }

    /// Makes `x` the current configuration, forgetting results elsewhere.
    fn move_to(&mut self, x: &[f64]) {
        if self.point != x {
            self.point.clear();
            self.point.extend_from_slice(x);
            self.jet_ready.iter_mut().for_each(|r| *r = false);
            for g in &mut self.groups {
                g.level = Level::Nothing;
            }
            self.reference_off.iter_mut().for_each(|o| *o = None);
        }
    }

    /// The jet of body `b` at the current configuration (second order, so that gradients
    /// and Hessians at one point share it).
    pub(crate) fn jet(&mut self, b: usize) -> &FrameJet {
        if !self.jet_ready[b] {
            // cannot fail: the point has one entry per coordinate and the assembly checked
            // the system's indices at its entry
            self.jet_ready[b] = self.system.bodies[b]
                .frame
                .jet(&self.point, JetOrder::Second, &mut self.jets[b])
                .is_ok();
        }
        &self.jets[b]
    }

    /// Brings every group to at least gradient (`hessians` false) or both Hessians at `x`,
    /// evaluating only what is not known there yet.
    pub(crate) fn evaluate(&mut self, x: &[f64], hessians: bool) {
        self.move_to(x);
        let want = if hessians {
            Level::Hessians
        } else {
            Level::Gradient
        };
        // jets first, for every body a term on the fast path reads
        if self.path == DerivativePath::Fast {
            for g in 0..self.groups.len() {
                if self.groups[g].level >= want || self.groups[g].fast == Some(false) {
                    continue;
                }
                let t = self.groups[g].members.first.0;
                if let Some(frames) = self.terms[t].frames() {
                    for &b in &frames.bodies {
                        if !self.jet_ready[b] {
                            // cannot fail, as in `Evaluator::jet`
                            self.jet_ready[b] = self.system.bodies[b]
                                .frame
                                .jet(&self.point, JetOrder::Second, &mut self.jets[b])
                                .is_ok();
                        }
                    }
                }
            }
        }
        for g in 0..self.groups.len() {
            if self.groups[g].level >= want {
                continue;
            }
            let start = self.timing.then(Instant::now);
            let fast = self.path == DerivativePath::Fast
                && self.groups[g].fast != Some(false)
                && self.evaluate_fast(g, hessians);
            if !fast {
                self.groups[g].fast = Some(false);
                self.evaluate_reference(g, hessians);
            } else {
                self.groups[g].fast = Some(true);
            }
            self.groups[g].level = want;
            if let (Some(start), true) = (start, hessians) {
                self.groups[g].time += start.elapsed();
                self.groups[g].timed += self.groups[g].members.len();
            }
        }
    }

    /// One fast evaluation of group `g`'s body; false if it has no fast path here.
    fn evaluate_fast(&mut self, g: usize, hessians: bool) -> bool {
        let group = &mut self.groups[g];
        let term = &self.terms[group.members.first.0];
        let Some(frames) = term.frames() else {
            return false;
        };
        let (n, parts) = (group.n, group.parts);
        self.local_x.clear();
        self.local_x
            .extend(term.coords.iter().map(|&i| self.point[i]));
        let values = &mut self.values[group.value_at..group.value_at + parts];
        let gradients = &mut self.gradients[group.gradient_at..group.gradient_at + parts * n];
        let scales = &mut self.force_scales[group.gradient_at..group.gradient_at + parts * n];
        let (on, off) = (&mut group.on, &mut group.off);
        values.fill(0.0);
        gradients.fill(0.0);
        scales.fill(0.0);
        if hessians {
            on.fill(0.0);
            off.fill(0.0);
        }
        let mut out = Derivatives {
            n,
            hessian: hessians,
            values,
            gradients,
            force_scales: scales,
            on,
            off,
            off_form: OffForm::Same,
            scratch: &mut self.scratch,
        };
        let jets = &self.jets;
        let view = |k: usize| FrameAt {
            jet: &jets[frames.bodies[k]],
            local: frames.frames[k].var_list(),
        };
        let x = &self.local_x;
        let done = on_stack(frames.bodies.len(), view, |frames| {
            term.fast_derivatives(&JetPoint { x, frames }, &mut out)
        }) == Some(true);
        let off_form = out.off_form;
        if done && hessians {
            group.off_form = off_form;
        }
        done
    }

    /// The reference path for every term of group `g`, one by one.
    fn evaluate_reference(&mut self, g: usize, hessians: bool) {
        let group = &mut self.groups[g];
        let n = group.n;
        let already = group.level >= Level::Gradient;
        for &(t, part) in group.members.iter() {
            let term = &self.terms[t];
            if !already {
                // the point has one entry per coordinate, which the terms read; were it not
                // so, NaN here makes the search stop with `NotFinite`
                let d =
                    term.reference_derivatives(&self.point)
                        .unwrap_or_else(|_| LocalDerivatives {
                            value: f64::NAN,
                            gradient: vec![f64::NAN; n],
                            hessian: vec![f64::NAN; n * n],
                        });
                self.values[group.value_at + part] = d.value;
                let at = group.gradient_at + part * n;
                self.gradients[at..at + n].copy_from_slice(&d.gradient);
                // rounding scale of the forces: a coordinate rounded by ε|x_b| moves force
                // a by ε |H_ab| |x_b| (the reference path has the Hessian at hand)
                for a in 0..n {
                    self.force_scales[at + a] = (0..n)
                        .map(|b| d.hessian[a * n + b].abs() * self.point[term.coords[b]].abs())
                        .sum();
                }
                group.on[part * n * n..(part + 1) * n * n].copy_from_slice(&d.hessian);
            }
            if hessians {
                // the point has one entry per coordinate, which the terms read
                self.reference_off[t] = match term.tension_off(&self.point) {
                    Ok(TensionOff::Unchanged) => Some(OffHessian::Same),
                    Ok(TensionOff::Vanishes) => Some(OffHessian::Zero),
                    Ok(TensionOff::Replaced(off)) => off
                        .reference_derivatives(&self.point)
                        .ok()
                        .map(|d| OffHessian::Matrix(d.hessian)),
                    Err(_) => None,
                };
            }
        }
    }

    fn slot(&self, t: usize) -> (&Group, usize) {
        let g = &self.groups[self.group_of[t]];
        let part = g
            .members
            .iter()
            .find(|&&(m, _)| m == t)
            .map_or(0, |&(_, p)| p);
        (g, part)
    }

    /// Energy (J) of term `t` at the current configuration.
    pub(crate) fn value(&self, t: usize) -> f64 {
        let (g, part) = self.slot(t);
        self.values[g.value_at + part]
    }

    /// Gradient of term `t` over its coordinates.
    pub(crate) fn gradient(&self, t: usize) -> &[f64] {
        let (g, part) = self.slot(t);
        let at = g.gradient_at + part * g.n;
        &self.gradients[at..at + g.n]
    }

    /// Rounding scale of term `t`'s gradient beyond its size (see
    /// [`pendkit_energy::Derivatives::force_scales`]).
    pub(crate) fn force_scale(&self, t: usize) -> &[f64] {
        let (g, part) = self.slot(t);
        let at = g.gradient_at + part * g.n;
        &self.force_scales[at..at + g.n]
    }

    /// Tension-on Hessian of term `t` (row-major over its coordinates).
    pub(crate) fn on(&self, t: usize) -> &[f64] {
        let (g, part) = self.slot(t);
        &g.on[part * g.n * g.n..(part + 1) * g.n * g.n]
    }

    /// The tension-off form of term `t` from its group's last fast evaluation (fixed per
    /// part for a shared body).
    fn off_form(&self, t: usize) -> OffForm {
        match self.terms[t].part_off() {
            Some(PartOff::Unchanged) => OffForm::Same,
            Some(PartOff::Vanishes) => OffForm::Zero,
            None => self.groups[self.group_of[t]].off_form,
        }
    }

    /// Hands over term `t`'s Hessians (tension on and off), the off term built at the
    /// current configuration, without copying them where the term has its body to itself;
    /// the group is left without its results.
    pub(crate) fn take_hessians(&mut self, t: usize) -> (Vec<f64>, OffHessian) {
        let form = self.off_form(t);
        let reference_off = self.reference_off[t].take();
        let g = &mut self.groups[self.group_of[t]];
        g.level = Level::Nothing;
        let off = match (reference_off, form) {
            (Some(off), _) => off,
            (None, OffForm::Same) => OffHessian::Same,
            (None, OffForm::Zero) => OffHessian::Zero,
            (None, OffForm::Written) => OffHessian::Matrix(std::mem::take(&mut g.off)),
        };
        if g.parts == 1 {
            return (std::mem::take(&mut g.on), off);
        }
        let part = g
            .members
            .iter()
            .find(|&&(m, _)| m == t)
            .map_or(0, |&(_, p)| p);
        let nn = g.n * g.n;
        (g.on[part * nn..(part + 1) * nn].to_vec(), off)
    }

    /// Time spent on Hessians per phase since the last call (phase name, time, terms
    /// evaluated), in the order the groups were added; phases with nothing evaluated are
    /// left out.
    pub(crate) fn take_times(&mut self) -> Vec<(String, Duration, usize)> {
        let mut out: Vec<(String, Duration, usize)> = Vec::new();
        for g in &mut self.groups {
            let (time, calls) = (std::mem::take(&mut g.time), std::mem::take(&mut g.timed));
            if calls == 0 {
                continue;
            }
            // `hessian:<kind>`, kinds joined by `+` for a body shared by two
            let phase = match g.kinds {
                [Some(a), Some(b)] => format!("hessian:{a}+{b}"),
                [Some(a), None] | [None, Some(a)] => format!("hessian:{a}"),
                [None, None] => "hessian".to_string(),
            };
            match out.iter_mut().find(|(name, ..)| *name == phase) {
                Some(entry) => {
                    entry.1 += time;
                    entry.2 += calls;
                }
                None => out.push((phase, time, calls)),
            }
        }
        out
    }
}
