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
