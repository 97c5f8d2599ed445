//! The bundled suspensions: the suspension files under `models/` embedded in the program and
//! listed by name, each a `pendkit_model::Model` read from its file on first use; and the
//! library through which a file's `extends` finds them.

use std::collections::BTreeMap;
use std::sync::{Arc, LazyLock, OnceLock};

use pendkit_model::{BuildError, DampingSpec, DefaultsCache, Model, ParameterInfo, ParsedDamping};
use pendkit_params::{ParamError, ParamSet, Resolved};
use pendkit_suspension::generate::{MAX_CHAIN_STAGES, chain};
use pendkit_suspension::{BundledFile, FileError, Generator, Library, Suspension};
use pendkit_system::System;

/// A bundled file: its name (what `extends` says) and the file (its path in the repository,
/// its text and its packed tree).
struct File {
    name: &'static str,
    /// Its `summary` as written (read at build time, so that a list of the models reads
    /// none of their files).
    summary: &'static str,
    file: BundledFile,
}

// `static FILES: [File; N]`, written by build.rs from its list of files
include!(concat!(env!("OUT_DIR"), "/files.rs"));

/// The bundled models, in the order `pendkit models` lists them: each is the file of its
/// name (`chain` is written by its generator for its parameter `n_stages`).
const MODELS: [&str; 17] = [
    "toy",
    "pendulum",
    "double-pendulum",
    "rigid-body",
    "chain",
    "quad",
    "quad-lite",
    "quad-full",
    "quad-lateral",
    "quad-v5",
    "quad-aligo",
    "arm-cavity",
    "triple",
    "triple-lite",
    "triple-full",
    "triple-lateral",
    "triple-v5",
];

/// The chain's generator: `n_stages` bodies (the bundled file is its text for 4).
pub const CHAIN: Generator = Generator {
    parameter: "n_stages",
    description: "number of bodies in the chain (1 to 200): the stages are written for it",
    range: (1, MAX_CHAIN_STAGES),
    default: 4,
    write: chain,
    summary: "n_stages (default 4) 40 kg bodies in a vertical chain, each on 4 vertical steel wires",
};

/// The bundled files, for `extends`.
pub struct Bundled;

impl Library for Bundled {
    fn file(&self, name: &str) -> Option<BundledFile> {
        let file_name = if name.ends_with(".toml") {
            name.to_string()
        } else {
            format!("{name}.toml")
        };
        FILES.iter().find(|f| f.name == file_name).map(|f| f.file)
    }
}

/// A bundled model: its name, and its file read on first use (a file that does not read
/// makes every use of the model fail with the file's error).
pub struct BundledModel {
    name: &'static str,
    loaded: OnceLock<Result<Suspension, FileError>>,
}

impl BundledModel {
    /// The model read from its file.
    pub fn suspension(&self) -> Result<&Suspension, FileError> {
        self.loaded
            .get_or_init(|| {
                if self.name == "chain" {
                    return Suspension::generated("models/basic/chain.toml", CHAIN, &Bundled);
                }
                Suspension::bundled(self.name, &Bundled)
            })
            .as_ref()
            .map_err(Clone::clone)
    }

    fn broken(&self, e: FileError) -> BuildError {
        BuildError::Invalid {
            item: format!("bundled model '{}'", self.name),
            message: e.to_string(),
        }
    }
}

impl Model for BundledModel {
    fn name(&self) -> &str {
        self.name
    }

    fn summary(&self) -> &str {
        if self.name == "chain" {
            return CHAIN.summary;
        }
        // every bundled model file writes its summary (the build read it)
        let file_name = format!("{}.toml", self.name);
        FILES
            .iter()
            .find(|f| f.name == file_name)
            .map_or("", |f| f.summary)
    }

    fn parameters(&self) -> Result<ParamSet, ParamError> {
        // a file that does not read has no parameters; its build reports the file's error
        self.suspension()
            .map_or_else(|_| Ok(ParamSet::new()), |s| s.parameters())
    }

    fn damping(&self) -> BTreeMap<String, DampingSpec> {
        self.suspension().map(|s| s.damping()).unwrap_or_default()
    }

    fn parsed_damping(&self) -> Result<BTreeMap<String, ParsedDamping>, BuildError> {
        self.suspension()
            .map_or_else(|_| Ok(BTreeMap::new()), |s| s.parsed_damping())
    }

    fn build(&self, params: &Resolved) -> Result<System, BuildError> {
        self.suspension().map_err(|e| self.broken(e))?.build(params)
    }

    fn build_tangents(
        &self,
        params: &Resolved,
        tangent: &pendkit_params::Tangent<pendkit_params::ChunkDual>,
    ) -> Result<pendkit_model::ChunkBuild, BuildError> {
        self.suspension()
            .map_err(|e| self.broken(e))?
            .build_tangents(params, tangent)
    }

    fn defaults_cache(&self) -> Option<&DefaultsCache> {
        self.suspension().ok().and_then(|s| s.defaults_cache())
    }

    fn parameter_info(&self, params: &Resolved) -> Result<Vec<ParameterInfo>, BuildError> {
        self.suspension()
            .map_err(|e| self.broken(e))?
            .parameter_info(params)
    }
}

static CATALOGUE: LazyLock<Vec<Arc<BundledModel>>> = LazyLock::new(|| {
    MODELS
        .iter()
        .map(|&name| {
            Arc::new(BundledModel {
                name,
                loaded: OnceLock::new(),
            })
        })
        .collect()
});

/// Every bundled model.
pub fn models() -> Vec<Arc<dyn Model>> {
    CATALOGUE
        .iter()
        .map(|m| Arc::clone(m) as Arc<dyn Model>)
        .collect()
}

/// The bundled model called `name`.
pub fn find(name: &str) -> Option<Arc<BundledModel>> {
    CATALOGUE.iter().find(|m| m.name == name).cloned()
}

/// The names of the bundled models.
pub fn names() -> &'static [&'static str] {
    &MODELS
}

/// The bundled files (name, repository path, text), for tests and tools.
pub fn files() -> impl Iterator<Item = (&'static str, &'static str, &'static str)> {
    FILES.iter().map(|f| (f.name, f.file.path, f.file.text))
}

#[cfg(test)]
mod tests {
    use super::*;
    // the kinds the bundled files' instances use, linked so that they are registered
    use pendkit_element_optical_spring as _;

    /// The bundled chain file is the generator's text for its default count, so that reading
    /// the file and generating it agree.
    #[test]
    fn chain_file_is_the_generators() {
        let file = Bundled.file("chain").unwrap();
        assert_eq!(file.text, chain(CHAIN.default).unwrap().source.text);
    }

    /// Each bundled model read from its packed tree is the model its text reads as: the same
    /// parameters and the same system (the text parsed here by the TOML reader, with the
    /// same files to extend).
    #[test]
    fn packed_files_read_as_their_text() {
        use pendkit_model::{Overrides, build_with};
        for name in names().iter().filter(|n| **n != "chain") {
            let file = Bundled.file(name).unwrap();
            let packed = Suspension::bundled(name, &Bundled).unwrap();
            let text = Suspension::from_text(file.path, file.text, &Bundled).unwrap();
            let (a, pa) = build_with(&packed, &Overrides::default()).unwrap();
            let (b, pb) = build_with(&text, &Overrides::default()).unwrap();
            let values = |r: &Resolved| format!("{:?}", r.iter().collect::<Vec<_>>());
            assert_eq!(values(&pa), values(&pb), "{name}");
            assert_eq!(format!("{a:?}"), format!("{b:?}"), "{name}");
        }
    }

    /// Each bundled file's stored description is the one its packed tree reads as, every
    /// value with its place (file, span and field path: what errors name), and so is its
    /// damping, as written and as parsed.
    #[test]
    fn stored_descriptions_are_the_files() {
        for (name, _, _) in files() {
            let file = Bundled.file(name).unwrap();
            assert!(!file.stored.is_empty(), "{name}");
            let (source, root) = file.read().unwrap();
            let read = Suspension::from_tree(source, root, &Bundled);
            let stored = Suspension::bundled(name, &Bundled);
            match (read, stored) {
                (Ok(a), Ok(b)) => {
                    assert_eq!(
                        format!("{:?}", a.spec()),
                        format!("{:?}", b.spec()),
                        "{name}"
                    );
                    assert_eq!(a.damping(), b.damping(), "{name}");
                    let parsed = |s: &Suspension| format!("{:?}", s.parsed_damping());
                    assert_eq!(parsed(&a), parsed(&b), "{name}");
                }
                // the materials file has no bodies: the same error either way
                (Err(a), Err(b)) => assert_eq!(a, b, "{name}"),
                (a, b) => panic!("{name}: {a:?} against {b:?}"),
            }
        }
    }

    /// Every bundled file reads (a broken file would only show when its model is built), and
    /// the summary listed without reading it is the one its model reads.
    #[test]
    fn every_bundled_model_reads() {
        for name in names() {
            let model = find(name).unwrap();
            let s = model.suspension().unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(s.name(), *name);
            assert!(!model.summary().is_empty(), "{name}");
            assert_eq!(model.summary(), s.summary(), "{name}");
        }
    }
}
