//! The stage's matrices on their fixed pattern against the straightforward dense scatter.
//!
//! `StageModel::new` builds the pattern and sums the terms' local Hessians row by row
//! (`pendkit_dynamics`); `Assembled::dilution_parts` scatters the same Hessians into dense
//! master matrices term by term, the textbook assembly (`pendkit_assembly`). Both add each
//! entry's contributions in term order starting from zero, so they must agree exactly
//! (bit for bit, tolerance zero): the lossless part, every damping tag's part and the mass
//! matrix; a tag missing from the pattern must have no non-zero entry; and every entry
//! the pattern leaves out must be exactly zero in every part.

use nalgebra::DMatrix;
use pendkit_system::Stage;
use pendkit_tests::run;

/// Models covering floats (xtra-lite blade tips), 6-DOF blade bodies, lateral compliance,
/// beads, the triple's couplings, chains and the small models.
const MODELS: [(&str, &[&str]); 9] = [
    ("toy", &[]),
    ("pendulum", &[]),
    ("rigid-body", &[]),
    ("quad", &[]),
    ("quad-full", &[]),
    ("quad-lateral", &[]),
    ("quad-v5", &[]),
    ("triple-lite", &[]),
    ("chain", &["n_stages=3"]),
];

#[test]
fn pattern_values_equal_the_dense_scatter() {
    for (name, sets) in MODELS {
        for stage in [Stage::S0B, Stage::S2] {
            let r = run(name, sets, stage);
            let m = &r.model;
            let (lossless, tags) = r.assembled.dilution_parts();
            assert_eq!(
                m.dense(&m.lossless).unwrap(),
                lossless,
                "{name} {stage}: lossless"
            );
            for (tag, dense) in &tags {
                match m.by_tag.iter().find(|(t, _)| t == tag) {
                    Some((_, values)) => {
                        assert_eq!(&m.dense(values).unwrap(), dense, "{name} {stage}: {tag}")
                    }
                    None => assert!(
                        dense.iter().all(|&x| x == 0.0),
                        "{name} {stage}: tag {tag} has entries but no part"
                    ),
                }
            }
            for (tag, _) in &m.by_tag {
                assert!(
                    tags.contains_key(tag),
                    "{name} {stage}: part {tag} of no term"
                );
            }
            let (nx, _, _) = m.sizes;
            let mass = m.dense(&m.mass_on_pattern).unwrap();
            assert_eq!(
                mass.view((0, 0), (nx, nx)),
                r.assembled.mass.to_dense().view((0, 0), (nx, nx)),
                "{name} {stage}: mass"
            );
            // nothing non-zero outside the pattern
            let dim = m.pattern.dim();
            let outside = DMatrix::from_fn(dim, dim, |i, j| m.pattern.slot(i, j).is_none());
            for (k, &out) in outside.iter().enumerate() {
                if out {
                    assert_eq!(
                        lossless[k], 0.0,
                        "{name} {stage}: lossless outside the pattern"
                    );
                    for (tag, dense) in &tags {
                        assert_eq!(dense[k], 0.0, "{name} {stage}: {tag} outside the pattern");
                    }
                }
            }
        }
    }
}
