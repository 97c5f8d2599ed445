//! Pinned floats that a stage holds only about some axes: a violin bead's clamped joint on a
//! slanted fibre in stage 1A. Before bending joins (1B), only torsion turns a joint, and
//! torsion holds its rotation about each segment's axis. The joint's floats are yaw, pitch
//! and roll about the lab axes: on a vertical fibre the twist is yaw alone and pitch and
//! roll are idle (exact zeros), but on a slanted fibre the twist axis mixes all three.
//!
//! Two directions of each joint are then not held by 1A's physics: the one perpendicular
//! to both segments, held by nothing, and the one in the plane of the kink the beads'
//! weight puts at the joint (the segments of a slanted fibre are a polygon, ε ~ 1e-8 rad
//! apart for quad-aligo's 5 beads, up to ~1e-4 for heavy beads on steel), held with a
//! stiffness ε² κ and pulled with ε κ. Eliminating that one would let the joints turn by
//! twist/ε and release the fibre's twist altogether (a chain of freely bending links
//! cannot resist twist), a linearisation far outside its range and not the stage's
//! physics: before bending the joints turn about the fibre only. So the joints' rotations
//! that the stage holds with less than [`HELD`] of its largest stiffness are held at zero
//! (left out of the stage, as the idle floats are), when they are pulled with less than
//! [`PULLED`] of it; a float that is pulled harder and held by nothing (a mistake in a
//! model) is kept, and the elimination reports it as before. From stage 1B, bending holds
//! every rotation of a joint at a stiffness of the order of the twist's and nothing is left
//! out.
//!
//! The floats kept are chosen by symmetric pivoting on the stage's float block (largest
//! remaining diagonal first): one per joint, the one nearest the fibre's axis.

use nalgebra::DMatrix;
use pendkit_energy::OffHessian;

use crate::TermMatrices;

/// A rotation held with at most this fraction of the float block's largest diagonal entry
/// is not held by the stage: ε² for a kink of ε = 1e-3 rad, above any a bead's weight puts
/// in a taut fibre (see the module's doc), and far below bending's stiffness relative to
/// torsion from 1B (of order 1 to 1e-2).
const HELD: f64 = 1e-6;

/// A rotation left out may move a term's forces by at most this fraction of the term's
/// largest Hessian entry (per unit rotation): ε for a kink of 1e-3 rad; a float that
/// something really pulls moves them by O(1).
const PULLED: f64 = 1e-3;

/// The floats of `candidates` (global indices; pinned and not idle) whose rotations the
/// stage's `terms` do not hold and that are held at zero (see the module's doc).
pub(crate) fn redundant_floats(terms: &[TermMatrices], candidates: &[usize]) -> Vec<usize> {
    if candidates.is_empty() {
        return Vec::new();
    }
    let size = terms
        .iter()
        .flat_map(|t| t.coords.iter().copied())
        .chain(candidates.iter().copied())
        .max()
        .map_or(0, |g| g + 1);
    let mut position = vec![None; size];
    for (i, &g) in candidates.iter().enumerate() {
        position[g] = Some(i);
    }
    let local = |g: usize| position[g];
    let n = candidates.len();
    // the float block of the stiffness (tension on) over the candidates
    let mut q = DMatrix::<f64>::zeros(n, n);
    for t in terms {
        let m = t.coords.len();
        for (a, &ga) in t.coords.iter().enumerate() {
            let Some(i) = local(ga) else { continue };
            for (b, &gb) in t.coords.iter().enumerate() {
                if let Some(j) = local(gb) {
                    q[(i, j)] += t.on[a * m + b];
                }
            }
        }
    }
    let mut out = Vec::new();
    for group in components(&q) {
        out.extend(left_out(terms, candidates, &q, &group));
    }
    out.sort_unstable();
    out
}

/// The connected groups of the candidates (indices into `q`) joined by non-zero entries.
fn components(q: &DMatrix<f64>) -> Vec<Vec<usize>> {
    let n = q.nrows();
    let mut group = vec![usize::MAX; n];
    let mut groups = Vec::new();
    for start in 0..n {
        if group[start] != usize::MAX {
            continue;
        }
        let id = groups.len();
        let mut members = vec![start];
        group[start] = id;
        let mut k = 0;
        while k < members.len() {
            let i = members[k];
            for j in 0..n {
                if group[j] == usize::MAX && (q[(i, j)] != 0.0 || q[(j, i)] != 0.0) {
                    group[j] = id;
                    members.push(j);
                }
            }
            k += 1;
        }
        members.sort_unstable();
        groups.push(members);
    }
    groups
}

/// The floats of one group (global indices) to leave out: those whose pivots are below
/// [`HELD`], if none of them is pulled (by more than [`PULLED`]); none otherwise.
fn left_out(
    terms: &[TermMatrices],
    candidates: &[usize],
    q: &DMatrix<f64>,
    group: &[usize],
) -> Vec<usize> {
    let size = group.len();
    let block = DMatrix::from_fn(size, size, |i, j| q[(group[i], group[j])]);
    let (kept, dropped) = pivot_split(&block);
    if dropped.is_empty() {
        return Vec::new();
    }
    // each left-out float d with the kept floats' response: n_d = e_d − Σ y_i e_kept_i,
    // Q_kk y = Q_kd (the direction of d that the kept floats cannot absorb)
    let q_kk = DMatrix::from_fn(kept.len(), kept.len(), |i, j| block[(kept[i], kept[j])]);
    let q_kd = DMatrix::from_fn(kept.len(), dropped.len(), |i, j| {
        block[(kept[i], dropped[j])]
    });
    let Some(y) = q_kk.lu().solve(&q_kd) else {
        return Vec::new();
    };
    let global = |i: usize| candidates[group[i]];
    // the terms that touch the group, and each direction as a dense vector over coordinates
    let members: Vec<usize> = group.iter().map(|&i| candidates[i]).collect();
    let touching: Vec<&TermMatrices> = terms
        .iter()
        .filter(|t| t.coords.iter().any(|g| members.contains(g)))
        .collect();
    let size = members.iter().max().map_or(0, |g| g + 1);
    for (c, &d) in dropped.iter().enumerate() {
        let mut direction = vec![0.0; size];
        direction[global(d)] = 1.0;
        for (r, &k) in kept.iter().enumerate() {
            direction[global(k)] = -y[(r, c)];
        }
        if !null_for_every_term(&touching, &direction) {
            return Vec::new();
        }
    }
    let mut out: Vec<usize> = dropped.iter().map(|&d| global(d)).collect();
    out.sort_unstable();
    out
}

/// Symmetric diagonal pivoting on `block` (symmetric): the positions whose pivots are above
/// [`HELD`] of the largest diagonal entry (kept, in pivot order), and the others.
fn pivot_split(block: &DMatrix<f64>) -> (Vec<usize>, Vec<usize>) {
    let n = block.nrows();
    let mut a = block.clone();
    let mut remaining: Vec<usize> = (0..n).collect();
    let mut kept = Vec::new();
    let largest = (0..n).fold(0.0f64, |m, i| m.max(a[(i, i)].abs()));
    while let Some((at, &p)) = remaining
        .iter()
        .enumerate()
        .max_by(|x, y| a[(*x.1, *x.1)].abs().total_cmp(&a[(*y.1, *y.1)].abs()))
    {
        let pivot = a[(p, p)];
        if pivot.abs() <= HELD * largest {
            break;
        }
        remaining.swap_remove(at);
        for &i in &remaining {
            let factor = a[(i, p)] / pivot;
            // the block is banded (a fibre's chain of joints): most rows are untouched
            if factor == 0.0 {
                continue;
            }
            for &j in &remaining {
                a[(i, j)] -= factor * a[(p, j)];
            }
        }
        kept.push(p);
    }
    remaining.sort_unstable();
    (kept, remaining)
}

/// Whether `direction` (a component per global coordinate, zero past its end) moves no
/// term's forces, tension on and off: |H_t n| ≤ [`PULLED`] of the term's largest
/// entry times n's largest component, on every row.
fn null_for_every_term(terms: &[&TermMatrices], direction: &[f64]) -> bool {
    let scale = direction.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    let component = |g: usize| direction.get(g).copied().unwrap_or(0.0);
    terms.iter().all(|t| {
        let m = t.coords.len();
        let matrices: [Option<&[f64]>; 2] = [
            Some(&t.on),
            match &t.off {
                OffHessian::Matrix(off) => Some(off),
                _ => None,
            },
        ];
        matrices.into_iter().flatten().all(|h| {
            let largest = h.iter().fold(0.0f64, |x, v| x.max(v.abs()));
            (0..m).all(|a| {
                let force: f64 = t
                    .coords
                    .iter()
                    .enumerate()
                    .map(|(b, &g)| h[a * m + b] * component(g))
                    .sum();
                force.abs() <= PULLED * largest * scale
            })
        })
    })
}
