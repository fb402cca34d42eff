//! The XML element helpers of the PLCopen reader: an element's child, text, localId and
//! position, and its words in a refusal.

use std::string::String;

use roxmltree::Node;

/// Words for an element in a refusal: `coil Lamp (localId 7)`.
pub(super) fn what(n: Node) -> String {
    let tag = n.tag_name().name();
    let id = n.attribute("localId").unwrap_or("?");
    let name = match tag {
        "contact" | "coil" => child_text(n, "variable"),
        "block" => n
            .attribute("instanceName")
            .or(n.attribute("typeName"))
            .map(str::to_string),
        "inVariable" | "outVariable" | "inOutVariable" => child_text(n, "expression"),
        _ => None,
    };
    match name {
        Some(v) => format!("{tag} {} (localId {id})", v.trim()),
        None => format!("{tag} (localId {id})"),
    }
}

/// `n`'s first child element named `tag`.
pub(super) fn child<'a, 'i>(n: Node<'a, 'i>, tag: &str) -> Option<Node<'a, 'i>> {
    n.children().find(|c| c.tag_name().name() == tag)
}

/// The trimmed text of `n`'s child `tag`.
pub(super) fn child_text(n: Node, tag: &str) -> Option<String> {
    child(n, tag).map(|c| c.text().unwrap_or("").trim().to_string())
}

/// An element's `localId`.
pub(super) fn local_id(n: Node) -> Option<u64> {
    n.attribute("localId").and_then(|s| s.trim().parse().ok())
}

/// An element's position (y, x): the order the picture shows it in.
pub(super) fn pos(n: Node) -> (i64, i64) {
    let p = child(n, "position");
    let num = |a: &str| {
        p.and_then(|p| p.attribute(a))
            .and_then(|v| v.trim().parse::<f64>().ok())
            .map_or(0, |v| v as i64)
    };
    (num("y"), num("x"))
}

/// How deep a document's elements nest, counted by a scan of its text without recursion
/// (roxmltree's parser recurses once per level, so a deep file is refused before it).
/// Comments, CDATA, processing instructions and declarations are skipped; quoted attribute
/// values may hold `>`.
pub(super) fn nesting(text: &str) -> usize {
    let b = text.as_bytes();
    let skip_to = |from: usize, end: &[u8]| -> usize {
        b[from..]
            .windows(end.len())
            .position(|w| w == end)
            .map_or(b.len(), |p| from + p + end.len())
    };
    let (mut i, mut depth, mut deepest) = (0, 0usize, 0);
    while let Some(p) = b[i..].iter().position(|&c| c == b'<') {
        i += p;
        let rest = &b[i..];
        if rest.starts_with(b"<!--") {
            i = skip_to(i + 4, b"-->");
        } else if rest.starts_with(b"<![CDATA[") {
            i = skip_to(i + 9, b"]]>");
        } else if rest.starts_with(b"<?") {
            i = skip_to(i + 2, b"?>");
        } else if rest.starts_with(b"<!") {
            i = skip_to(i + 2, b">");
        } else if rest.starts_with(b"</") {
            depth = depth.saturating_sub(1);
            i = skip_to(i + 2, b">");
        } else {
            // An open tag: to its `>` outside quotes; `/>` closes it at once.
            let mut quote = None;
            let mut j = i + 1;
            while j < b.len() {
                match (quote, b[j]) {
                    (None, q @ (b'"' | b'\'')) => quote = Some(q),
                    (Some(q), c) if c == q => quote = None,
                    (None, b'>') => break,
                    _ => {}
                }
                j += 1;
            }
            if b.get(j.saturating_sub(1)) != Some(&b'/') || j == i + 1 {
                depth += 1;
                deepest = deepest.max(depth);
            }
            i = j + 1;
        }
        if i >= b.len() {
            break;
        }
    }
    deepest
}
