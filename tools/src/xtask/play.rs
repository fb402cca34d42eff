//! `./x play --build` (`xtask play`): the playground as a static site in `out/play/`, which
//! any static host serves as it is (docs/PLAY.md). Relative paths only, no server API,
//! nothing from another origin:
//!
//! - the page (`play/page/`), its `index.html` given the import map written here;
//! - the adapter (`play/sim/`, the real image in avr8js) and avr8js's ES modules (npm,
//!   `play/package-lock.json`), xterm.js as `utile live`'s page pins it, and `utile live`'s
//!   look and element builder (`live/live.css`, `live/dom.js`);
//! - the firmware image (`out/m328-nano-utile.hex`, from `cargo fw`);
//! - the WebAssembly module (`play/wasm/`, built here for `wasm32-unknown-unknown` by the
//!   pinned nightly with `-Z build-std=std,panic_abort`);
//! - every example of `examples/` and `examples/index.json`, the list the page shows.
//!
//! avr8js's modules import each other without the `.js` a browser needs (its package is
//! made for bundlers); the import map maps each such URL to its file, and the build fails
//! when one of their imports would not resolve.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{bail, Context};

/// The WebAssembly target and the profile the module is built with (`Cargo.toml`).
const WASM_TARGET: &str = "wasm32-unknown-unknown";
const WASM_PROFILE: &str = "play";
/// The module's file in the site.
const WASM_FILE: &str = "utile_play.wasm";
/// The firmware image, from `cargo fw`, and its name in the site.
const FIRMWARE_HEX: &str = "m328-nano-utile.hex";
/// Where index.html wants the import map.
const IMPORT_MAP_MARK: &str = "<!-- import map: written by ./x play --build -->";
/// xterm.js from `utile live`'s page libraries (one pinned version for both pages):
/// (file under its node_modules, name in the site's `vendor/`).
const XTERM: [(&str, &str); 2] = [
    ("@xterm/xterm/lib/xterm.mjs", "xterm.mjs"),
    ("@xterm/xterm/css/xterm.css", "xterm.css"),
];
/// What the playground takes of `utile live`'s own page (`tools/src/live/page/`), the same
/// files, not copies in the repository: its look and its element builder.
const LIVE_FILES: [&str; 2] = ["live.css", "dom.js"];
/// avr8js's ES modules under `play/node_modules`, and their folder in the site.
const AVR8JS: &str = "avr8js/dist/esm";
const AVR8JS_SITE: &str = "vendor/avr8js";

/// What went into the site: files and bytes.
pub struct Built {
    /// The site's folder.
    pub out: PathBuf,
    /// How many files it has.
    pub files: usize,
    /// Their bytes.
    pub bytes: u64,
    /// The WebAssembly module's bytes.
    pub wasm_bytes: u64,
    /// How many examples the page lists.
    pub examples: usize,
}

/// Builds the site from the repository at `root` into `out` (emptied first).
pub fn build(root: &Path, out: &Path) -> anyhow::Result<Built> {
    let hex = root.join("out").join(FIRMWARE_HEX);
    if !hex.is_file() {
        bail!("{} is missing: run cargo fw first", hex.display());
    }
    let avr8js = root.join("play/node_modules").join(AVR8JS);
    let page_libs = root.join("tools/src/live/page/node_modules");
    for needed in [avr8js.join("index.js"), page_libs.join(XTERM[0].0)] {
        if !needed.is_file() {
            bail!(
                "{} is missing: run ./x setup (npm ci in play/ and tools/src/live/page/)",
                needed.display()
            );
        }
    }
    let wasm = build_wasm(root)?;

    if out.exists() {
        std::fs::remove_dir_all(out).with_context(|| format!("cannot empty {}", out.display()))?;
    }
    let mut site = Site::new(out);
    let avr8js_modules = site.tree(&avr8js, Path::new(AVR8JS_SITE), "js")?;
    check_imports(out)?;
    let mut index = None;
    for entry in files_in(&root.join("play/page"))? {
        let name = entry.file_name().context("a page file")?;
        if name == "index.html" {
            index = Some(entry);
        } else {
            site.copy(&entry, Path::new(name))?;
        }
    }
    site.tree(&root.join("play/sim"), Path::new("sim"), "js")?;
    for name in LIVE_FILES {
        let from = root.join("tools/src/live/page").join(name);
        site.copy(&from, &Path::new("live").join(name))?;
    }
    for (file, name) in XTERM {
        site.copy(&page_libs.join(file), &Path::new("vendor").join(name))?;
    }
    site.copy(&hex, Path::new(FIRMWARE_HEX))?;
    let index = index.context("play/page/ has no index.html")?;
    let html = std::fs::read_to_string(&index)
        .with_context(|| format!("cannot read {}", index.display()))?;
    if !html.contains(IMPORT_MAP_MARK) {
        bail!("{} has no place for the import map", index.display());
    }
    let head = head(&import_map(&avr8js_modules)?, &site.modules());
    site.write(
        Path::new("index.html"),
        html.replace(IMPORT_MAP_MARK, &head),
    )?;
    let wasm_bytes = site.copy(&wasm, Path::new(WASM_FILE))?;
    let examples = examples(&mut site, &root.join("examples"))?;
    Ok(Built {
        out: out.to_path_buf(),
        files: site.files,
        bytes: site.bytes,
        wasm_bytes,
        examples,
    })
}

/// `cargo build` of `play/wasm/` for the browser; the `.wasm` file it made.
fn build_wasm(root: &Path) -> anyhow::Result<PathBuf> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let status = Command::new(cargo)
        .current_dir(root)
        .args([
            "build",
            "-q",
            "-p",
            "utile-play",
            "--lib",
            "--target",
            WASM_TARGET,
            "--profile",
            WASM_PROFILE,
            "-Z",
            "build-std=std,panic_abort",
        ])
        .status()
        .context("cannot run cargo")?;
    if !status.success() {
        bail!("the WebAssembly module (play/wasm/) did not build");
    }
    Ok(root
        .join("target")
        .join(WASM_TARGET)
        .join(WASM_PROFILE)
        .join(WASM_FILE))
}

/// The site being written: its folder and what went in.
struct Site {
    out: PathBuf,
    files: usize,
    bytes: u64,
    /// The URLs of its JavaScript modules, in the order written.
    modules: Vec<String>,
}

impl Site {
    fn new(out: &Path) -> Self {
        Site {
            out: out.to_path_buf(),
            files: 0,
            bytes: 0,
            modules: Vec::new(),
        }
    }

    /// `bytes` as the site's file `name`.
    fn write(&mut self, name: &Path, bytes: impl AsRef<[u8]>) -> anyhow::Result<u64> {
        let to = self.out.join(name);
        if let Some(dir) = to.parent() {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create {}", dir.display()))?;
        }
        let bytes = bytes.as_ref();
        std::fs::write(&to, bytes).with_context(|| format!("cannot write {}", to.display()))?;
        self.files += 1;
        self.bytes += bytes.len() as u64;
        if name.extension().is_some_and(|e| e == "js" || e == "mjs") {
            self.modules.push(url(name));
        }
        Ok(bytes.len() as u64)
    }

    /// The URLs of its modules, sorted.
    fn modules(&self) -> Vec<String> {
        let mut m = self.modules.clone();
        m.sort();
        m
    }

    /// The file `from` as the site's file `name`.
    fn copy(&mut self, from: &Path, name: &Path) -> anyhow::Result<u64> {
        let bytes =
            std::fs::read(from).with_context(|| format!("cannot read {}", from.display()))?;
        self.write(name, bytes)
    }

    /// Every `.ext` file under `from` into the site's folder `to`, the tree kept; their names
    /// in the site, sorted.
    fn tree(&mut self, from: &Path, to: &Path, ext: &str) -> anyhow::Result<Vec<PathBuf>> {
        let mut names = Vec::new();
        let mut dirs = vec![from.to_path_buf()];
        while let Some(dir) = dirs.pop() {
            for path in entries(&dir)? {
                if path.is_dir() {
                    dirs.push(path);
                } else if path.extension().is_some_and(|e| e == ext) {
                    let name = to.join(path.strip_prefix(from).unwrap_or(&path));
                    self.copy(&path, &name)?;
                    names.push(name);
                }
            }
        }
        names.sort();
        Ok(names)
    }
}

/// What index.html gets where its mark is: the import map, then a `modulepreload` for every
/// module (fetched side by side, not one import after the other) and a `preload` of the
/// firmware image (fetched while the modules load).
fn head(map: &str, modules: &[String]) -> String {
    let mut head = format!("<script type=\"importmap\">\n{map}\n</script>\n");
    for m in modules {
        head.push_str(&format!("<link rel=\"modulepreload\" href=\"{m}\">\n"));
    }
    head.push_str(&format!(
        "<link rel=\"preload\" href=\"./{FIRMWARE_HEX}\" as=\"fetch\" crossorigin=\"anonymous\">"
    ));
    head
}

/// The entries of `dir`, sorted.
fn entries(dir: &Path) -> anyhow::Result<Vec<PathBuf>> {
    let mut list: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("cannot read {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    list.sort();
    Ok(list)
}

/// The files (not folders) of `dir`, sorted.
fn files_in(dir: &Path) -> anyhow::Result<Vec<PathBuf>> {
    Ok(entries(dir)?.into_iter().filter(|p| p.is_file()).collect())
}

/// A site path as a URL relative to the page (`./vendor/avr8js/cpu/cpu.js`).
fn url(name: &Path) -> String {
    format!("./{}", name.to_string_lossy().replace('\\', "/"))
}

/// The page's import map: `avr8js` to its entry module, and each of its modules' URLs
/// without `.js` (as they import each other) to the file. Fails when a module imports
/// something the map does not resolve.
fn import_map(modules: &[PathBuf]) -> anyhow::Result<String> {
    let site_dir = Path::new(AVR8JS_SITE);
    let mut imports = BTreeMap::new();
    imports.insert("avr8js".to_string(), url(&site_dir.join("index.js")));
    for m in modules {
        imports.insert(url(&m.with_extension("")), url(m));
    }
    let json = serde_json::json!({ "imports": imports });
    serde_json::to_string_pretty(&json).context("the import map")
}

/// Checks that every relative import of avr8js's modules (in the site at `out`) names one
/// of its modules, which the import map then resolves; how many there are.
fn check_imports(out: &Path) -> anyhow::Result<usize> {
    let root = out.join(AVR8JS_SITE);
    let mut checked = 0;
    let mut dirs = vec![root.clone()];
    while let Some(dir) = dirs.pop() {
        for path in entries(&dir)? {
            if path.is_dir() {
                dirs.push(path);
                continue;
            }
            let js = std::fs::read_to_string(&path)
                .with_context(|| format!("cannot read {}", path.display()))?;
            for spec in relative_imports(&js) {
                let target = normalize(&path.parent().unwrap_or(&root).join(format!("{spec}.js")));
                if !target.is_file() {
                    bail!(
                        "{} imports {spec}: no module {} (avr8js's layout changed: the import \
                         map of tools/src/xtask/play.rs needs a new rule)",
                        path.display(),
                        target.display()
                    );
                }
                checked += 1;
            }
        }
    }
    Ok(checked)
}

/// The relative specifiers a module imports or re-exports (`from './cpu/cpu'`).
fn relative_imports(js: &str) -> Vec<&str> {
    let mut found = Vec::new();
    for (at, _) in js.match_indices("from ") {
        let rest = &js[at + 5..];
        let Some(quote) = rest.chars().next().filter(|c| *c == '"' || *c == '\'') else {
            continue;
        };
        if let Some(end) = rest[1..].find(quote) {
            let spec = &rest[1..1 + end];
            if spec.starts_with("./") || spec.starts_with("../") {
                found.push(spec);
            }
        }
    }
    found
}

/// `a/b/../c` as `a/c`.
fn normalize(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for part in path.components() {
        match part {
            std::path::Component::ParentDir => {
                out.pop();
            }
            std::path::Component::CurDir => {}
            other => out.push(other),
        }
    }
    out
}

/// Every `.utl` of `examples/` (its sub-folders too) into the site's `examples/`, and
/// `examples/index.json`: `[{"name", "file", "title", "text"}]`, the title the listing's
/// first comment line, the text the listing (the page makes its `.hex` in the click). Returns how many.
fn examples(site: &mut Site, dir: &Path) -> anyhow::Result<usize> {
    let mut list = Vec::new();
    let names = site.tree(dir, Path::new("examples"), "utl")?;
    for name in names {
        let rel = name.strip_prefix("examples").unwrap_or(&name);
        let text = std::fs::read_to_string(dir.join(rel))
            .with_context(|| format!("cannot read {}", rel.display()))?;
        let title = text
            .lines()
            .find_map(|l| l.trim().strip_prefix('#'))
            .map(|t| t.trim().to_string())
            .unwrap_or_default();
        let file = rel.to_string_lossy().replace('\\', "/");
        list.push(serde_json::json!({
            "name": file.trim_end_matches(".utl"),
            "file": format!("examples/{file}"),
            "title": title,
            "text": text,
        }));
    }
    let count = list.len();
    let json = serde_json::to_string_pretty(&list).context("the examples' index")?;
    site.write(Path::new("examples/index.json"), json)?;
    Ok(count)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_imports_are_found_and_others_left() {
        let js =
            "export { CPU } from './cpu/cpu';\nimport { x } from \"../a/b\";\nimport 'avr8js';";
        assert_eq!(relative_imports(js), vec!["./cpu/cpu", "../a/b"]);
        assert_eq!(normalize(Path::new("a/b/../c/./d")), PathBuf::from("a/c/d"));
    }
}
