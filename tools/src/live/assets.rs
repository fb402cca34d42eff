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

#[cfg(test)]
mod tests {
    use super::*;

    /// The page's import map (`<script type="importmap">` in index.html): name → URL.
    fn import_map() -> serde_json::Map<String, serde_json::Value> {
        let (_, html) = get("/").expect("the page is served at /");
        let html = std::str::from_utf8(html).expect("index.html is UTF-8");
        let start = html
            .find("<script type=\"importmap\">")
            .expect("index.html has an import map");
        let json = &html[start..];
        let json = &json[json.find('>').unwrap() + 1..json.find("</script>").unwrap()];
        let map: serde_json::Value = serde_json::from_str(json).expect("the import map is JSON");
        map["imports"].as_object().expect("its \"imports\"").clone()
    }

    /// What a module imports: the specifiers after `from`, `import` and `import(`.
    fn imports(js: &str) -> Vec<&str> {
        let mut found = Vec::new();
        for key in ["from ", "import ", "import("] {
            for (at, _) in js.match_indices(key) {
                let rest = &js[at + key.len()..];
                let Some(quote) = rest.chars().next().filter(|c| *c == '"' || *c == '\'') else {
                    continue;
                };
                if let Some(end) = rest[1..].find(quote) {
                    found.push(&rest[1..1 + end]);
                }
            }
        }
        found
    }

    #[test]
    fn every_module_the_page_imports_is_served_and_every_name_is_mapped() {
        if let Err(e) = check() {
            panic!("{e}");
        }
        let map = import_map();
        for (name, url) in &map {
            let url = url.as_str().expect("a URL");
            let (kind, _) = get(url).unwrap_or_else(|| panic!("{name} maps to {url}: not served"));
            assert!(
                kind.starts_with("text/javascript"),
                "{url} is served as {kind}"
            );
        }
        let mut used = std::collections::BTreeSet::new();
        for (path, kind, body) in ASSETS {
            if !kind.starts_with("text/javascript") {
                continue;
            }
            let js = std::str::from_utf8(body).expect("a module is UTF-8");
            for spec in imports(js) {
                if spec.starts_with('/') {
                    assert!(get(spec).is_some(), "{path} imports {spec}: not served");
                } else {
                    assert!(
                        map.contains_key(spec),
                        "{path} imports {spec}: not in the import map"
                    );
                    used.insert(spec);
                }
            }
        }
        let unused: Vec<_> = map.keys().filter(|k| !used.contains(k.as_str())).collect();
        assert!(
            unused.is_empty(),
            "mapped but imported by no module: {unused:?}"
        );
        assert!(used.contains("@codemirror/view"), "{used:?}");
    }

    #[test]
    fn only_the_listed_files_of_the_libraries_are_served() {
        assert!(get("/vendor/@codemirror/view.js").is_some());
        assert!(get("/node_modules/@codemirror/view/dist/index.js").is_none());
        assert!(get("/vendor/@codemirror/view/dist/index.cjs").is_none());
        assert!(get("/package.json").is_none() && get("/package-lock.json").is_none());
    }
}
