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

/// Why the page cannot be served, when the libraries were missing at build time.
pub fn check() -> Result<(), String> {
    if MISSING.is_empty() {
        return Ok(());
    }
    Err(format!(
        "this utile was built without the page's libraries ({}): run ./x setup (it runs \
         npm ci in tools/src/live/page), then build again",
        MISSING.join(", ")
    ))
}
