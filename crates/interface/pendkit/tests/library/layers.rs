//! The crates' folders are layers (docs/architecture.md): a crate depends only on crates of
//! its own layer or a lower one, and the crates the document says are leaves depend on no
//! other pendkit crate. Read from the manifests themselves, so a dependency added against
//! the layering fails here rather than in a reader's head.

use std::collections::BTreeMap;
use std::path::Path;

/// The layer of a workspace folder, lowest first; `None` for folders outside the layering
/// (tests, benches and examples may use anything).
fn layer(path: &str) -> Option<(u8, &'static str)> {
    let layers: [(&str, (u8, &str)); 6] = [
        ("crates/base/", (0, "base")),
        ("crates/mechanics/", (1, "mechanics")),
        ("elements/", (1, "elements")),
        ("crates/description/", (2, "description")),
        ("models/", (2, "models")),
        ("crates/interface/", (3, "interface")),
    ];
    layers
        .into_iter()
        .find(|(prefix, _)| path.starts_with(prefix))
        .map(|(_, l)| l)
}

fn manifest(path: &Path) -> toml::Table {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.parse()
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Each pendkit package's folder, from the root manifest's `[workspace.dependencies]`,
/// and each one's pendkit dependencies (normal ones: what ships).
fn packages() -> BTreeMap<String, (String, Vec<String>)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../..");
    let workspace = manifest(&root.join("Cargo.toml"));
    let deps = workspace["workspace"]["dependencies"]
        .as_table()
        .expect("[workspace.dependencies]");
    let mut packages = BTreeMap::new();
    for (name, spec) in deps {
        let Some(path) = spec.get("path").and_then(|p| p.as_str()) else {
            continue;
        };
        let own = manifest(&root.join(path).join("Cargo.toml"));
        let uses = own
            .get("dependencies")
            .and_then(|d| d.as_table())
            .map(|d| {
                d.keys()
                    .filter(|k| deps.get(*k).is_some_and(|s| s.get("path").is_some()))
                    .cloned()
                    .collect()
            })
            .unwrap_or_default();
        packages.insert(name.clone(), (format!("{path}/"), uses));
    }
    packages
}

#[test]
fn every_crate_depends_only_on_its_own_layer_or_lower_ones() {
    let packages = packages();
    assert!(
        packages.len() > 15,
        "found only {} packages",
        packages.len()
    );
    let mut wrong = Vec::new();
    for (name, (path, uses)) in &packages {
        let Some((rank, layer_name)) = layer(path) else {
            continue;
        };
        for used in uses {
            let (used_path, _) = &packages[used];
            if let Some((used_rank, used_layer)) = layer(used_path)
                && used_rank > rank
            {
                wrong.push(format!("{name} ({layer_name}) uses {used} ({used_layer})"));
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "dependencies against the layering: {wrong:?}"
    );
}

#[test]
fn the_leaves_and_the_dynamics_stay_as_the_architecture_says() {
    let packages = packages();
    let uses = |name: &str| &packages[name].1;
    // leaves: no other pendkit crate
    for leaf in [
        "pendkit-expr",
        "pendkit-limits",
        "pendkit-rotations",
        "pendkit-source",
        "pendkit-export",
    ] {
        assert!(uses(leaf).is_empty(), "{leaf} uses {:?}", uses(leaf));
    }
    // the figures know no physics: they use only the one file writer (export's), so that a
    // figure is written whole or not at all like every other output
    assert_eq!(uses("pendkit-plot"), &["pendkit-export".to_string()]);
    // the data model computes no energy; the dynamics and noise work on assembled
    // matrices, not on terms
    for crate_ in ["pendkit-system", "pendkit-dynamics", "pendkit-noise"] {
        assert!(
            !uses(crate_).iter().any(|u| u == "pendkit-energy"),
            "{crate_} uses pendkit-energy"
        );
    }
    // element kinds are plug-ins: nothing in the core uses one (the facade links them)
    for (name, (path, used)) in &packages {
        if path.starts_with("crates/") && name != "pendkit" {
            assert!(
                !used.iter().any(|u| u.starts_with("pendkit-element-")),
                "{name} uses an element crate: {used:?}"
            );
        }
    }
}
