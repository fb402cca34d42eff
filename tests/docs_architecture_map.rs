//! docs/ARCHITECTURE.md is a true map of the repository: its file tables name every file
//! once and nothing else, and its crate table lists each crate's dependencies as the crate's
//! `Cargo.toml` has them. The rules are the map's own ("This map is kept true"): a name in
//! the first column of a table headed "file" is relative to the folder its section's heading
//! names (the root when it names none); a name ending in `/` covers a whole folder.
//!
//! The files are `git ls-files` (tracked, plus new files git does not ignore); without git,
//! the files on disk less what the `.gitignore` files exclude.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::process::Command;

/// The repository.
fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The names between backticks in `text`.
fn ticks(text: &str) -> Vec<&str> {
    text.split('`').skip(1).step_by(2).collect()
}

/// The cells of a table row.
fn cells(line: &str) -> Vec<&str> {
    let inner = line.trim().trim_start_matches('|').trim_end_matches('|');
    inner.split('|').map(str::trim).collect()
}

/// A Markdown table: its header's cells and its rows (with their line numbers), and the
/// folder of the section it is in.
struct Table<'a> {
    folder: String,
    header: Vec<&'a str>,
    rows: Vec<(usize, Vec<&'a str>)>,
}

/// Every table of `doc`.
fn tables(doc: &str) -> Vec<Table<'_>> {
    let lines: Vec<&str> = doc.lines().collect();
    let mut out = Vec::new();
    let mut folder = String::new();
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        if line.starts_with('#') {
            folder = ticks(line)
                .into_iter()
                .rev()
                .find(|t| t.ends_with('/'))
                .map(|t| t.trim_start_matches("./").to_string())
                .unwrap_or_default();
        }
        let is_table = line.starts_with('|')
            && lines
                .get(i + 1)
                .is_some_and(|next| next.starts_with("|---") || next.starts_with("|:"));
        if !is_table {
            i += 1;
            continue;
        }
        let mut table = Table {
            folder: folder.clone(),
            header: cells(line),
            rows: Vec::new(),
        };
        i += 2;
        while i < lines.len() && lines[i].starts_with('|') {
            table.rows.push((i + 1, cells(lines[i])));
            i += 1;
        }
        out.push(table);
    }
    out
}

/// The repository's files, from git when it is there.
fn files() -> BTreeSet<String> {
    let git = Command::new("git")
        .args([
            "ls-files",
            "-z",
            "--cached",
            "--others",
            "--exclude-standard",
        ])
        .current_dir(root())
        .output();
    match git {
        Ok(out) if out.status.success() => String::from_utf8_lossy(&out.stdout)
            .split('\0')
            .filter(|f| !f.is_empty() && root().join(f).is_file())
            .map(String::from)
            .collect(),
        _ => {
            let mut found = BTreeSet::new();
            walk(root(), "", &[], &mut found);
            found
        }
    }
}

/// One `.gitignore` line, as this fallback understands it: `/name` (that path below the
/// ignore file's folder), `name` or `name/` (any file or folder of that name below it),
/// `*.ext` (any file ending so).
#[derive(Clone)]
struct Ignore {
    base: String,
    pattern: String,
}

impl Ignore {
    fn matches(&self, rel: &str) -> bool {
        let Some(below) = rel.strip_prefix(&self.base) else {
            return false;
        };
        let p = self.pattern.trim_end_matches('/');
        if let Some(anchored) = p.strip_prefix('/') {
            return below == anchored || below.starts_with(&format!("{anchored}/"));
        }
        if let Some(ext) = p.strip_prefix('*') {
            return below.ends_with(ext);
        }
        below.split('/').any(|part| part == p)
    }
}

/// The files below `dir` (relative path `rel`), less what `.gitignore` files exclude.
fn walk(dir: &Path, rel: &str, ignores: &[Ignore], found: &mut BTreeSet<String>) {
    let mut ignores = ignores.to_vec();
    if let Ok(text) = std::fs::read_to_string(dir.join(".gitignore")) {
        for line in text.lines().map(str::trim) {
            if !line.is_empty() && !line.starts_with('#') {
                ignores.push(Ignore {
                    base: rel.to_string(),
                    pattern: line.to_string(),
                });
            }
        }
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let path = format!("{rel}{name}");
        if name == ".git" || ignores.iter().any(|i| i.matches(&path)) {
            continue;
        }
        let Ok(kind) = entry.file_type() else {
            continue;
        };
        if kind.is_dir() {
            walk(&entry.path(), &format!("{path}/"), &ignores, found);
        } else {
            found.insert(path);
        }
    }
}

#[test]
fn the_map_names_every_file_once_and_nothing_else() {
    let doc = std::fs::read_to_string(root().join("docs/ARCHITECTURE.md")).expect("the map");
    // Each name of the map, with the line that names it.
    let mut names: BTreeMap<String, usize> = BTreeMap::new();
    let mut problems = Vec::new();
    for table in tables(&doc).iter().filter(|t| t.header[0] == "file") {
        for (line, row) in &table.rows {
            for name in ticks(row[0]) {
                let path = format!("{}{name}", table.folder);
                if let Some(first) = names.insert(path.clone(), *line) {
                    problems.push(format!(
                        "`{path}` is named twice (lines {first} and {line})"
                    ));
                }
            }
        }
    }
    let files = files();
    assert!(files.len() > 100, "found only {} files", files.len());
    let mut used: BTreeSet<&str> = BTreeSet::new();
    for file in &files {
        let covering: Vec<&String> = names
            .keys()
            .filter(|n| *n == file || (n.ends_with('/') && file.starts_with(n.as_str())))
            .collect();
        match covering.as_slice() {
            [] => problems.push(format!("{file} has no line in the map")),
            [one] => {
                used.insert(one.as_str());
            }
            many => problems.push(format!("{file} is named by {many:?}")),
        }
    }
    for (name, line) in &names {
        if !used.contains(name.as_str()) {
            problems.push(format!(
                "line {line} names `{name}`, which is not in the repository"
            ));
        }
    }
    assert!(
        problems.is_empty(),
        "docs/ARCHITECTURE.md does not match the repository:\n  {}",
        problems.join("\n  ")
    );
}

/// A crate's name and its dependencies from its `Cargo.toml`: (used, used by its tests).
fn manifest(text: &str) -> (String, BTreeSet<String>, BTreeSet<String>) {
    let (mut name, mut deps, mut dev) = (String::new(), BTreeSet::new(), BTreeSet::new());
    let mut section = String::new();
    for line in text.lines().map(str::trim) {
        if line.starts_with('[') {
            section = line.trim_matches(['[', ']']).to_string();
            // `[dependencies.name]`: one dependency as a table.
            if let Some(dep) = section.strip_prefix("dependencies.") {
                deps.insert(dep.to_string());
            } else if let Some(dep) = section.strip_prefix("dev-dependencies.") {
                dev.insert(dep.to_string());
            }
            continue;
        }
        let key = line
            .split(['=', '.'])
            .next()
            .unwrap_or("")
            .trim()
            .to_string();
        if key.is_empty() || key.starts_with('#') {
            continue;
        }
        if section == "package" && key == "name" {
            name = line
                .split('=')
                .nth(1)
                .unwrap_or("")
                .trim()
                .trim_matches('"')
                .to_string();
        } else if section == "dev-dependencies" {
            dev.insert(key);
        } else if section == "dependencies"
            || section == "build-dependencies"
            || (section.starts_with("target.") && section.ends_with(".dependencies"))
        {
            deps.insert(key);
        }
    }
    (name, deps, dev)
}

#[test]
fn the_crate_table_lists_each_crates_dependencies() {
    let doc = std::fs::read_to_string(root().join("docs/ARCHITECTURE.md")).expect("the map");
    let tables = tables(&doc);
    let table = tables
        .iter()
        .find(|t| t.header[0] == "crate")
        .expect("a table headed `crate`");
    let column = |name: &str| {
        table
            .header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("the crate table has no column `{name}`"))
    };
    let (folder_at, uses_at, tests_at) = (
        column("folder"),
        column("uses"),
        column("its tests also use"),
    );
    let mut problems = Vec::new();
    let mut folders = BTreeSet::new();
    for (line, row) in &table.rows {
        let folder = ticks(row[folder_at])[0]
            .trim_start_matches("./")
            .to_string();
        let text = std::fs::read_to_string(root().join(&folder).join("Cargo.toml"))
            .unwrap_or_else(|e| panic!("line {line}: {folder}Cargo.toml: {e}"));
        let (name, deps, dev) = manifest(&text);
        let set = |cell: &str| -> BTreeSet<String> {
            ticks(cell).into_iter().map(String::from).collect()
        };
        if ticks(row[0]).first() != Some(&name.as_str()) {
            problems.push(format!("line {line}: {folder}Cargo.toml is `{name}`"));
        }
        if set(row[uses_at]) != deps {
            problems.push(format!(
                "line {line}: `{name}` uses {deps:?}, the map says {:?}",
                set(row[uses_at])
            ));
        }
        if set(row[tests_at]) != dev {
            problems.push(format!(
                "line {line}: `{name}`'s tests also use {dev:?}, the map says {:?}",
                set(row[tests_at])
            ));
        }
        folders.insert(folder);
    }
    // Every member of the workspace has its row.
    let workspace = std::fs::read_to_string(root().join("Cargo.toml")).expect("Cargo.toml");
    let members = workspace
        .lines()
        .find(|l| l.trim_start().starts_with("members"))
        .expect("workspace members");
    for member in members.split('"').skip(1).step_by(2) {
        let folder = match member {
            "." => String::new(),
            m => format!("{m}/"),
        };
        if !folders.contains(&folder) {
            problems.push(format!("the workspace member `{member}` has no row"));
        }
    }
    assert!(
        problems.is_empty(),
        "docs/ARCHITECTURE.md's crate table does not match the manifests:\n  {}",
        problems.join("\n  ")
    );
}
