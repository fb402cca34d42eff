//! What OpenPLC Editor and its compiler (xml2st) need of an exported PLCopen LD body
//! (`ladder_export`): every connection has its route, as the editor writes it and the
//! compiler reads a block's output; every contact and coil has one modifier (negated, an
//! edge, set or reset), as the editor draws them — the compiler keeps only the negation of
//! a contact that is both.

/// An element's absolute point: its position plus a `relPosition`.
fn point(el: roxmltree::Node, rel: roxmltree::Node) -> (i64, i64) {
    let num = |n: roxmltree::Node, a: &str| -> i64 { n.attribute(a).unwrap().parse().unwrap() };
    let p = el
        .children()
        .find(|c| c.has_tag_name("position"))
        .expect("an element's position");
    let r = rel
        .children()
        .find(|c| c.has_tag_name("relPosition"))
        .expect("a connection point's relPosition");
    (num(p, "x") + num(r, "x"), num(p, "y") + num(r, "y"))
}

/// Every connection of an LD body has its route: at least two `<position>`s, the first
/// where its input is, the last at the output it leaves (for a block, the output its
/// formalParameter names), each step horizontal or vertical — as OpenPLC Editor writes
/// them and as its compiler (xml2st) reads a block's output. The number of connections.
pub fn check_routes(xml: &str) -> Result<usize, String> {
    let doc = roxmltree::Document::parse(xml).map_err(|e| e.to_string())?;
    let body = doc
        .descendants()
        .find(|n| n.has_tag_name("LD"))
        .ok_or("no LD body")?;
    let by_id = |id: &str| {
        body.children()
            .find(|n| n.attribute("localId") == Some(id))
            .ok_or(format!("no element {id}"))
    };
    let mut count = 0;
    for cpi in body
        .descendants()
        .filter(|n| n.has_tag_name("connectionPointIn"))
    {
        let el = cpi
            .ancestors()
            .find(|a| a.parent() == Some(body))
            .ok_or("an input outside an element")?;
        let at_in = point(el, cpi);
        for c in cpi.children().filter(|c| c.has_tag_name("connection")) {
            count += 1;
            let what = format!(
                "connection into {} {:?}",
                el.tag_name().name(),
                el.attribute("localId")
            );
            let pts: Vec<(i64, i64)> = c
                .children()
                .filter(|p| p.has_tag_name("position"))
                .map(|p| {
                    (
                        p.attribute("x").unwrap().parse().unwrap(),
                        p.attribute("y").unwrap().parse().unwrap(),
                    )
                })
                .collect();
            if pts.len() < 2 {
                return Err(format!("{what}: {} positions", pts.len()));
            }
            if pts[0] != at_in {
                return Err(format!(
                    "{what}: starts at {:?}, its input is at {at_in:?}",
                    pts[0]
                ));
            }
            if pts.windows(2).any(|w| w[0].0 != w[1].0 && w[0].1 != w[1].1) {
                return Err(format!("{what}: a slanted step in {pts:?}"));
            }
            let src = by_id(c.attribute("refLocalId").ok_or("no refLocalId")?)?;
            let outs: Vec<roxmltree::Node> = match c.attribute("formalParameter") {
                Some(f) if src.has_tag_name("block") => src
                    .descendants()
                    .filter(|v| {
                        v.has_tag_name("variable") && v.attribute("formalParameter") == Some(f)
                    })
                    .flat_map(|v| {
                        v.children()
                            .filter(|o| o.has_tag_name("connectionPointOut"))
                    })
                    .collect(),
                _ => src
                    .children()
                    .filter(|o| o.has_tag_name("connectionPointOut"))
                    .collect(),
            };
            let end = *pts.last().unwrap();
            if !outs.iter().any(|&o| point(src, o) == end) {
                return Err(format!(
                    "{what}: ends at {end:?}, not at an output of {} {:?}",
                    src.tag_name().name(),
                    src.attribute("localId")
                ));
            }
        }
    }
    Ok(count)
}

/// `xml` with every connection's route (its `<position>`s) left out.
pub fn without_routes(xml: &str) -> String {
    let mut out = String::new();
    let mut rest = xml;
    while let Some(i) = rest.find("<connection ") {
        let (head, tail) = rest.split_at(i);
        out.push_str(head);
        let open = &tail[..=tail.find('>').unwrap()];
        if open.ends_with("/>") {
            out.push_str(open);
            rest = &tail[open.len()..];
            continue;
        }
        out.push_str(&open[..open.len() - 1]);
        out.push_str("/>");
        let close = tail.find("</connection>").unwrap();
        rest = &tail[close + "</connection>".len()..];
    }
    out.push_str(rest);
    out
}

/// Every contact and coil of an LD body has at most one modifier: negated, a rising or
/// falling edge, or (a coil) set or reset. The number of contacts and coils.
pub fn check_modifiers(xml: &str) -> Result<usize, String> {
    let doc = roxmltree::Document::parse(xml).map_err(|e| e.to_string())?;
    let mut count = 0;
    for n in doc
        .descendants()
        .filter(|n| n.has_tag_name("contact") || n.has_tag_name("coil"))
    {
        count += 1;
        let set = |a: &str, off: &str| n.attribute(a).is_some_and(|v| v != off);
        let modifiers = usize::from(set("negated", "false"))
            + usize::from(set("edge", "none"))
            + usize::from(set("storage", "none"));
        if modifiers > 1 {
            return Err(format!(
                "{} {:?}: {modifiers} modifiers",
                n.tag_name().name(),
                n.attribute("localId")
            ));
        }
    }
    Ok(count)
}
