//! The page's files, built into the binary by `tools/build.rs`: the HTML, CSS and JS modules
//! of `page/` and the libraries fetched from the npm registry (xterm.js, uPlot).

include!(concat!(env!("OUT_DIR"), "/page.rs"));

/// The file at URL `path`: its content type and bytes.
pub fn get(path: &str) -> Option<(&'static str, &'static [u8])> {
    ASSETS
        .iter()
        .find(|(p, _, _)| *p == path)
        .map(|(_, t, b)| (*t, *b))
}

/// The page's libraries were missing when this binary was built.
#[derive(Debug, thiserror::Error)]
#[error(
    "this utile was built without the page's libraries ({}): run ./x setup (it runs npm ci \
     in tools/src/live/page), then build again",
    .0.join(", ")
)]
pub struct LibrariesMissing(pub Vec<&'static str>);

/// Why the page cannot be served, when the libraries were missing at build time.
pub fn check() -> Result<(), LibrariesMissing> {
    if MISSING.is_empty() {
        return Ok(());
    }
    Err(LibrariesMissing(MISSING.to_vec()))
}
