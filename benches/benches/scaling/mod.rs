//! The scaling cases the bench files share: the `chain` model at several sizes.

use pendkit::Case;

/// Numbers of stages of the `chain` scaling benches: 60, 180 and 600 variables (40, 120 and
/// 400 wires).
pub const CHAIN_STAGES: [usize; 3] = [10, 30, 100];

/// The `chain` model with `n_stages = n`, and its bench name `chain-<n>`.
pub fn chain(n: usize) -> (String, Case) {
    let name = format!("chain-{n}");
    let case = Case::model("chain")
        .and_then(|case| case.with_sets(&[format!("n_stages={n}")]))
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    (name, case)
}
