//! Reads the bundled suspension files at build time and packs their trees
//! (`pendkit_source::packed`), so that the program embeds them already read and needs no TOML
//! parser; then stores each one's description as read, merged with what it extends
//! (`pendkit_suspension::stored`), so that running a bundled model reads no file at all. A
//! bundled file that does not read fails the build, naming its line.

use std::path::{Path, PathBuf};
use std::{env, fs};

use pendkit_source::{Source, packed, tree};
use pendkit_suspension::{BundledFile, Library, stored};

/// Every bundled file: its folder under `models/` and its name.
const FILES: [(&str, &str); 18] = [
    ("basic", "toy.toml"),
    ("basic", "pendulum.toml"),
    ("basic", "double-pendulum.toml"),
    ("basic", "rigid-body.toml"),
    ("basic", "chain.toml"),
    ("ligo", "ligo-materials.toml"),
    ("ligo", "quad.toml"),
    ("ligo", "quad-lite.toml"),
    ("ligo", "quad-full.toml"),
    ("ligo", "quad-lateral.toml"),
    ("ligo", "quad-v5.toml"),
    ("ligo", "quad-aligo.toml"),
    ("ligo", "arm-cavity.toml"),
    ("ligo", "triple.toml"),
    ("ligo", "triple-lite.toml"),
    ("ligo", "triple-full.toml"),
    ("ligo", "triple-lateral.toml"),
    ("ligo", "triple-v5.toml"),
];

/// The bundled files as the build has them: each file's name and the file, text and packed
/// tree (leaked: a build script's strings live as long as it does).
struct Files(Vec<(&'static str, BundledFile)>);

impl Library for Files {
    fn file(&self, name: &str) -> Option<BundledFile> {
        let file_name = if name.ends_with(".toml") {
            name.to_string()
        } else {
            format!("{name}.toml")
        };
        self.0.iter().find(|f| f.0 == file_name).map(|f| f.1)
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = PathBuf::from(env::var("OUT_DIR")?);
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    // every file's tree first: a description reads the files its file extends
    let mut files = Files(Vec::new());
    let mut summaries = Vec::new();
    for (dir, name) in FILES {
        let path = models.join(dir).join(name).canonicalize()?;
        println!("cargo::rerun-if-changed={}", path.display());
        let repo_path = format!("models/{dir}/{name}");
        let text = fs::read_to_string(&path)?;
        let root = tree::parse(&Source::new(repo_path.as_str(), None, text.as_str()))?;
        // the file's own `summary`, so that listing the models reads none of them
        summaries.push(match &root.value {
            tree::Value::Table(t) => match t.get("summary").map(|n| &n.value) {
                Some(tree::Value::Str(s)) => s.clone(),
                _ => String::new(),
            },
            _ => String::new(),
        });
        let file = BundledFile {
            path: repo_path.leak(),
            text: text.leak(),
            packed: packed::pack(&root).leak(),
            stored: &[],
        };
        files.0.push((name, file));
    }
    let mut table = format!(
        "/// Every bundled file (written by build.rs).\nstatic FILES: [File; {}] = [\n",
        FILES.len()
    );
    for (((dir, name), file), summary) in FILES.iter().zip(&files.0).zip(&summaries) {
        let packed_path = out.join(format!("{dir}-{name}.packed"));
        fs::write(&packed_path, file.1.packed)?;
        let stored_path = out.join(format!("{dir}-{name}.stored"));
        fs::write(&stored_path, stored::store_bundled(name, &files)?)?;
        let path = models.join(dir).join(name).canonicalize()?;
        table += &format!(
            "    File {{ name: {name:?}, summary: {summary:?}, file: BundledFile {{ path: {:?}, \
             text: include_str!({:?}), packed: include_str!({:?}), \
             stored: include_bytes!({:?}) }} }},\n",
            file.1.path,
            path.display().to_string(),
            packed_path.display().to_string(),
            stored_path.display().to_string(),
        );
    }
    table += "];\n";
    fs::write(out.join("files.rs"), table)?;
    Ok(())
}
