//! A fibre's held resonances: the frequencies at which its dynamic stiffness is infinite,
//! the modes of the fibre alone with both end frames held (docs/continuum-fibres.md,
//! "Violin modes"). The whole model's violin modes are searched around them
//! (`pendkit_dynamics::StageModel::violin_modes`), which needs every one of them in a band
//! to count the model's roots there: the transverse ones of both planes, and the axial and
//! torsional ones.

use pendkit_dynamics::HeldResonance;

use crate::{C64, ContinuumFibre, Local, Moduli};

/// The motion of each one-dimensional problem, in the order of [`crosses`].
const MOTIONS: [&str; 4] = ["transverse", "transverse", "axial", "torsion"];

/// The cross stiffness (end 0 to end 1) of each one-dimensional problem: the two beams'
/// (w₀, w₁), the axial wave's and the twist wave's. Each has a pole at every resonance of
/// its problem with both ends held, where its inverse changes sign through zero.
fn crosses(l: &Local) -> [C64; 4] {
    [
        l.planes[0][(0, 2)],
        l.planes[1][(0, 2)],
        l.axial[(0, 1)],
        l.torsion[(0, 1)],
    ]
}

/// The real parts of `m` alone: the lossless problem whose roots the search brackets.
fn lossless(m: &Moduli) -> Moduli {
    Moduli {
        stretch: C64::new(m.stretch.re, 0.0),
        bending: C64::new(m.bending.re, 0.0),
        torsion: C64::new(m.torsion.re, 0.0),
    }
}

impl ContinuumFibre {
    /// The ideal string's fundamental √(T l/m)/2l (Hz), m the fibre's mass: the scale of
    /// the scan for held resonances.
    pub fn string_fundamental(&self) -> f64 {
        let mass: f64 = self.pieces.iter().map(|q| q.density * q.length).sum();
        let length = self.length();
        (self.tension * length / mass).sqrt() / (2.0 * length)
    }

    /// The inverse cross stiffnesses of the lossless problem at `f` (Hz) with the real
    /// parts of `moduli(f)`.
    fn inverse_crosses(&self, f: f64, moduli: &dyn Fn(f64) -> Moduli) -> [f64; 4] {
        let local = self.local(2.0 * std::f64::consts::PI * f, &lossless(&moduli(f)));
        crosses(&local).map(|z| 1.0 / z.re)
    }

    /// Scans from `start` (Hz) up in steps of 1/64 of the string's fundamental for the
    /// zeros of each inverse cross stiffness (sign changes, bisected to the last bit; a
    /// pole of the inverse, where it also changes sign, is told apart by its size at the
    /// bisection's end), calling `found(motion, f)` for each held resonance in ascending
    /// order per step, until `found` returns false or `steps` steps are done.
    pub(crate) fn scan_held(
        &self,
        start: f64,
        steps: usize,
        moduli: &dyn Fn(f64) -> Moduli,
        found: &mut dyn FnMut(usize, f64) -> bool,
    ) {
        let step = self.string_fundamental() / 64.0;
        let (mut a, mut ga) = (start, self.inverse_crosses(start, moduli));
        for _ in 0..steps {
            let b = a + step;
            let gb = self.inverse_crosses(b, moduli);
            let mut roots: Vec<(f64, usize)> = Vec::new();
            for m in 0..MOTIONS.len() {
                if ga[m] * gb[m] >= 0.0 {
                    continue;
                }
                let g = |f: f64| self.inverse_crosses(f, moduli)[m];
                let (mut lo, mut hi) = (a, b);
                while hi - lo > f64::EPSILON * hi {
                    let mid = 0.5 * (lo + hi);
                    if g(mid) * ga[m] > 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                let root = 0.5 * (lo + hi);
                if g(root).abs() < ga[m].abs().min(gb[m].abs()) {
                    roots.push((root, m));
                }
            }
            roots.sort_by(|x, y| x.0.total_cmp(&y.0));
            for (root, m) in roots {
                if !found(m, root) {
                    return;
                }
            }
            (a, ga) = (b, gb);
        }
    }

    /// The held resonances in [`lo`, `hi`] (Hz), each once per one-dimensional problem
    /// (a round fibre's transverse ones twice: its two planes), with the complex
    /// multipliers `moduli(f)`: found with their real parts, and Im f to first order in the
    /// loss, −Im g(f₀)/g′(f₀) with g the inverse cross stiffness (complex multipliers in
    /// g, real ones in g′), which vanishes at the complex resonance.
    pub fn held_in(&self, lo: f64, hi: f64, moduli: &dyn Fn(f64) -> Moduli) -> Vec<HeldResonance> {
        let mut roots = Vec::new();
        let steps = ((hi - lo) / (self.string_fundamental() / 64.0))
            .ceil()
            .max(1.0);
        // at most a few million steps: the band is a few harmonics wide
        let steps = steps.min(1e7) as usize;
        self.scan_held(lo, steps, moduli, &mut |m, f| {
            if f <= hi {
                roots.push((m, f));
            }
            f <= hi
        });
        roots
            .into_iter()
            .map(|(m, f)| {
                let complex = self.local(2.0 * std::f64::consts::PI * f, &moduli(f));
                let g_imag = (C64::new(1.0, 0.0) / crosses(&complex)[m]).im;
                // g′ by a central difference over 1e-6 f: g is smooth on the scale of the
                // half-harmonic to its next pole
                let h = 1e-6 * f;
                let slope = (self.inverse_crosses(f + h, moduli)[m]
                    - self.inverse_crosses(f - h, moduli)[m])
                    / (2.0 * h);
                HeldResonance {
                    frequency_hz: f,
                    imag_hz: -g_imag / slope,
                    motion: MOTIONS[m],
                }
            })
            .collect()
    }
}
