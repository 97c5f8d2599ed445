//! Reads the bundled suspension files at build time and packs their trees
//! (`pendkit_source::packed`), so that the program embeds them already read and needs no TOML
//! parser; a bundled file that does not read fails the build, naming its line.

use std::path::{Path, PathBuf};
use std::{env, fs};

use pendkit_source::{Source, packed, tree};

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

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = PathBuf::from(env::var("OUT_DIR")?);
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut table = format!(
        "/// Every bundled file (written by build.rs).\nstatic FILES: [File; {}] = [\n",
        FILES.len()
    );
    for (dir, name) in FILES {
        let path = models.join(dir).join(name).canonicalize()?;
        println!("cargo::rerun-if-changed={}", path.display());
        let repo_path = format!("models/{dir}/{name}");
        let text = fs::read_to_string(&path)?;
        let root = tree::parse(&Source::new(repo_path.as_str(), None, text))?;
        let packed_path = out.join(format!("{dir}-{name}.packed"));
        fs::write(&packed_path, packed::pack(&root))?;
        // the file's own `summary`, so that listing the models reads none of them
        let summary = match &root.value {
            tree::Value::Table(t) => match t.get("summary").map(|n| &n.value) {
                Some(tree::Value::Str(s)) => s.clone(),
                _ => String::new(),
            },
            _ => String::new(),
        };
        table += &format!(
            "    File {{ name: {name:?}, summary: {summary:?}, file: BundledFile {{ path: {repo_path:?}, \
             text: include_str!({:?}), packed: include_str!({:?}) }} }},\n",
            path.display().to_string(),
            packed_path.display().to_string(),
        );
    }
    table += "];\n";
    fs::write(out.join("files.rs"), table)?;
    Ok(())
}
