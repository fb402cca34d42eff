//! Builds `utile live`'s page into the binary: every file of `src/live/page/` (HTML, CSS, JS
//! modules) and the libraries `./x setup` fetches from the npm registry into
//! `src/live/page/node_modules/` (`npm ci`, from the committed lock file). Without them the
//! build still succeeds (so `cargo fw` and the other tools never depend on npm), and
//! `utile live` says to run `./x setup` instead of serving a page that cannot work.

use std::fmt::Write as _;
use std::path::Path;

/// The libraries the page loads, and nothing else of node_modules: (URL path, file under
/// node_modules). CodeMirror's modules import each other by their npm names; the import map
/// of `index.html` maps each name to its URL here (`/vendor/NAME.js`).
const VENDOR: [(&str, &str); 16] = [
    ("/vendor/xterm.mjs", "@xterm/xterm/lib/xterm.mjs"),
    ("/vendor/xterm.css", "@xterm/xterm/css/xterm.css"),
    ("/vendor/uplot.mjs", "uplot/dist/uPlot.esm.js"),
    ("/vendor/uplot.css", "uplot/dist/uPlot.min.css"),
    // The Program tab's editor: CodeMirror 6 and what its modules import.
    (
        "/vendor/@codemirror/state.js",
        "@codemirror/state/dist/index.js",
    ),
    (
        "/vendor/@codemirror/view.js",
        "@codemirror/view/dist/index.js",
    ),
    (
        "/vendor/@codemirror/commands.js",
        "@codemirror/commands/dist/index.js",
    ),
    (
        "/vendor/@codemirror/language.js",
        "@codemirror/language/dist/index.js",
    ),
    (
        "/vendor/@codemirror/lint.js",
        "@codemirror/lint/dist/index.js",
    ),
    (
        "/vendor/@codemirror/streamparser.js",
        "@codemirror/streamparser/dist/index.js",
    ),
    ("/vendor/@lezer/common.js", "@lezer/common/dist/index.js"),
    (
        "/vendor/@lezer/highlight.js",
        "@lezer/highlight/dist/index.js",
    ),
    (
        "/vendor/@marijn/find-cluster-break.js",
        "@marijn/find-cluster-break/src/index.js",
    ),
    ("/vendor/crelt.js", "crelt/index.js"),
    ("/vendor/style-mod.js", "style-mod/src/style-mod.js"),
    ("/vendor/w3c-keyname.js", "w3c-keyname/index.js"),
];

fn content_type(name: &str) -> &'static str {
    match name.rsplit('.').next() {
        Some("html") => "text/html; charset=utf-8",
        Some("css") => "text/css; charset=utf-8",
        Some("js") | Some("mjs") => "text/javascript; charset=utf-8",
        Some("svg") => "image/svg+xml",
        Some("png") => "image/png",
        _ => "application/octet-stream",
    }
}

fn main() {
    let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let page = Path::new(&manifest).join("src/live/page");
    // Cargo looks at every file under the folder: node_modules appearing triggers a rebuild.
    println!("cargo:rerun-if-changed={}", page.display());
    let mut table = String::from("/// The page's files: URL path, content type, bytes.\n");
    table.push_str("pub static ASSETS: &[(&str, &str, &[u8])] = &[\n");
    let mut own: Vec<_> = std::fs::read_dir(&page)
        .expect("tools/src/live/page")
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.is_file())
        .filter(|p| {
            let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
            !name.starts_with("package") && !name.starts_with('.')
        })
        .collect();
    own.sort();
    for path in &own {
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        let url = if name == "index.html" {
            "/".to_string()
        } else {
            format!("/{name}")
        };
        let _ = writeln!(
            table,
            "    ({url:?}, {:?}, include_bytes!({:?})),",
            content_type(name),
            path.display().to_string()
        );
    }
    let mut missing = Vec::new();
    for (url, file) in VENDOR {
        let path = page.join("node_modules").join(file);
        if path.is_file() {
            let _ = writeln!(
                table,
                "    ({url:?}, {:?}, include_bytes!({:?})),",
                content_type(file),
                path.display().to_string()
            );
        } else {
            missing.push(file);
        }
    }
    table.push_str("];\n");
    let _ = writeln!(
        table,
        "/// Libraries that were not fetched when this was built (`./x setup` fetches them).\n\
         pub static MISSING: &[&str] = &{missing:?};"
    );
    let out = Path::new(&std::env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join("page.rs");
    std::fs::write(out, table).expect("write page.rs");
}
