//! The body's elements read in file order (also inside CODESYS's rungs and networks): each
//! by localId, the connectors by name, the block instances, the variables the body reads
//! and writes; unknown elements, jumps and labels refused.

use super::*;

/// What the body holds, besides the elements the reader keeps.
pub(super) struct Found<'a, 'i> {
    /// The elements in file order.
    pub(super) order: Vec<Node<'a, 'i>>,
    /// Each variable name the body uses (upper-cased), with the first element using it.
    pub(super) used: Vec<(String, Node<'a, 'i>)>,
    /// Each variable name a coil or output variable writes, with the first one.
    pub(super) written: Vec<(String, Node<'a, 'i>)>,
    seen: HashSet<String>,
    seen_written: HashSet<String>,
}

const ELEMENTS: [&str; 10] = [
    "leftPowerRail",
    "rightPowerRail",
    "contact",
    "coil",
    "block",
    "inVariable",
    "outVariable",
    "inOutVariable",
    "connector",
    "continuation",
];

/// Every element of the body `lang` into the reader; what it uses.
pub(super) fn collect<'a, 'i>(r: &mut Reader<'a, 'i>, lang: Node<'a, 'i>) -> Found<'a, 'i> {
    let mut found = Found {
        order: Vec::new(),
        used: Vec::new(),
        written: Vec::new(),
        seen: HashSet::new(),
        seen_written: HashSet::new(),
    };
    let mut stack: Vec<Node> = lang.children().filter(|c| c.is_element()).collect();
    stack.reverse();
    while let Some(n) = stack.pop() {
        let tag = n.tag_name().name();
        match tag {
            "rung" | "network" => {
                let mut kids: Vec<Node> = n.children().filter(|c| c.is_element()).collect();
                kids.reverse();
                stack.extend(kids);
                continue;
            }
            "comment" | "addData" | "documentation" => continue,
            "jump" | "label" | "return" => {
                r.fail(n, CAUSE, "jumps and returns have no uTile form — every rung runs every scan; redraw without them");
                continue;
            }
            t if !ELEMENTS.contains(&t) => {
                r.fail(n, CAUSE, &format!(
                    "<{t}> is not an element uTile knows (rails, contacts, coils, TON/TOF/TP/CTU/R_TRIG/F_TRIG/SR/RS, AND/OR/XOR/NOT, variables) — remove it"
                ));
                continue;
            }
            _ => {}
        }
        let Some(id) = local_id(n) else {
            r.fail(
                n,
                DETAIL,
                "no localId — save the file again from the editor",
            );
            continue;
        };
        if let Some(first) = r.elems.insert(id, n) {
            r.elems.insert(id, first);
            r.fail(
                n,
                DETAIL,
                &format!("two elements share localId {id} — save the file again from the editor"),
            );
            continue;
        }
        note(r, &mut found, n, id);
        found.order.push(n);
    }
    found
}

/// An element's instance, connector name and variable.
fn note<'a, 'i>(r: &mut Reader<'a, 'i>, found: &mut Found<'a, 'i>, n: Node<'a, 'i>, id: u64) {
    let tag = n.tag_name().name();
    match tag {
        "block" => {
            if let Some(inst) = n.attribute("instanceName") {
                let ty = n.attribute("typeName").unwrap_or("").to_ascii_uppercase();
                r.instances.push((inst.trim().into(), id, ty));
            }
        }
        "connector" => {
            if let Some(name) = n.attribute("name") {
                r.connectors.insert(name.to_ascii_uppercase(), n);
            }
        }
        _ => {}
    }
    let Some(name) = name_in(n).map(|s| s.to_ascii_uppercase()) else {
        return;
    };
    if name.is_empty() || matches!(name.as_str(), "TRUE" | "FALSE" | "0" | "1") {
        return;
    }
    if found.seen.insert(name.clone()) {
        found.used.push((name.clone(), n));
    }
    if matches!(tag, "coil" | "outVariable" | "inOutVariable")
        && found.seen_written.insert(name.clone())
    {
        found.written.push((name, n));
    }
}

/// The variable an element names: a contact's or coil's variable, an in- or out-variable's
/// expression.
pub(super) fn name_in(n: Node) -> Option<String> {
    match n.tag_name().name() {
        "contact" | "coil" => child_text(n, "variable"),
        "inVariable" | "outVariable" | "inOutVariable" => child_text(n, "expression"),
        _ => None,
    }
}
