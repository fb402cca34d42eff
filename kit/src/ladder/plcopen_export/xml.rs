//! The XML of `utile export`: the project around the program, and the LD body's elements
//! (the power rails, contacts, coils, constants, blocks) at their places, each connection
//! with its route.

use std::fmt::Write as _;
use std::string::String;
use std::vec::Vec;

use super::graph::{Element, Kind, RAIL};
use super::layout::{in_rel, out_rel, Layout};

/// The project: one program POU named after `name` with `vars` and the LD `body`, a
/// configuration, a resource and a task running it.
pub(super) fn project(name: &str, vars: &str, body: &str) -> String {
    let pou: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    let pou = if pou.starts_with(|c: char| c.is_ascii_alphabetic()) {
        pou
    } else {
        format!("p_{pou}")
    };
    format!(
        r#"<?xml version="1.0" encoding="utf-8"?>
<project xmlns="http://www.plcopen.org/xml/tc6_0201" xmlns:xhtml="http://www.w3.org/1999/xhtml" xmlns:xsd="http://www.w3.org/2001/XMLSchema">
  <fileHeader companyName="uTile" productName="{pou}" productVersion="1" creationDateTime="2026-01-01T00:00:00"/>
  <contentHeader name="{pou}" modificationDateTime="2026-01-01T00:00:00">
    <coordinateInfo>
      <fbd><scaling x="10" y="10"/></fbd>
      <ld><scaling x="10" y="10"/></ld>
      <sfc><scaling x="10" y="10"/></sfc>
    </coordinateInfo>
  </contentHeader>
  <types>
    <dataTypes/>
    <pous>
      <pou name="{pou}" pouType="program">
        <interface>
          <localVars>
{vars}          </localVars>
        </interface>
        <body>
          <LD>
{body}          </LD>
        </body>
      </pou>
    </pous>
  </types>
  <instances>
    <configurations>
      <configuration name="Config0">
        <resource name="Res0">
          <task name="task0" priority="0" interval="T#20ms">
            <pouInstance name="instance0" typeName="{pou}"/>
          </task>
        </resource>
      </configuration>
    </configurations>
  </instances>
</project>
"#
    )
}

fn point(s: &mut String, tag: &str, (x, y): (i32, i32)) {
    let _ = write!(s, "<{tag} x=\"{x}\" y=\"{y}\"/>");
}

/// A connection from `id` (its output `formal`) along `route`.
fn connection(s: &mut String, id: u32, formal: Option<&str>, route: &[(i32, i32)]) {
    let _ = write!(s, "<connection refLocalId=\"{id}\"");
    if let Some(f) = formal {
        let _ = write!(s, " formalParameter=\"{f}\"");
    }
    s.push('>');
    for &p in route {
        point(s, "position", p);
    }
    s.push_str("</connection>");
}

/// Input `k` of element `i`: its point and its wires' routes.
fn input(s: &mut String, els: &[Element], at: &Layout, i: usize, k: usize) {
    s.push_str("<connectionPointIn>");
    point(s, "relPosition", in_rel(&els[i], k));
    for &src in &els[i].inputs[k].1 {
        connection(s, src.0, src.1, &at.route(els, i, k, src));
    }
    s.push_str("</connectionPointIn>");
}

fn output(s: &mut String, e: &Element, k: usize) {
    s.push_str("<connectionPointOut>");
    point(s, "relPosition", out_rel(e, k));
    s.push_str("</connectionPointOut>");
}

/// One element, one line.
fn element(s: &mut String, els: &[Element], at: &Layout, i: usize) {
    let (e, p) = (&els[i], at.at[i]);
    let (id, w, h) = (e.id, p.w, p.h);
    let size = format!("localId=\"{id}\" height=\"{h}\" width=\"{w}\"");
    s.push_str("            ");
    match &e.kind {
        Kind::Contact { var, negated, edge }
        | Kind::Coil {
            var,
            negated,
            storage: edge,
        } => {
            let tag = if matches!(e.kind, Kind::Contact { .. }) {
                "contact"
            } else {
                "coil"
            };
            let (edge, storage) = match e.kind {
                Kind::Contact { .. } => (*edge, "none"),
                _ => ("none", *edge),
            };
            let _ = write!(
                s,
                "<{tag} {size} negated=\"{negated}\" edge=\"{edge}\" storage=\"{storage}\">"
            );
            point(s, "position", (p.x, p.y));
            input(s, els, at, i, 0);
            output(s, e, 0);
            let _ = write!(s, "<variable>{var}</variable></{tag}>");
        }
        Kind::Const(text) => {
            let _ = write!(s, "<inVariable {size} negated=\"false\">");
            point(s, "position", (p.x, p.y));
            output(s, e, 0);
            let _ = write!(s, "<expression>{text}</expression></inVariable>");
        }
        Kind::Block { ty, instance } => {
            let _ = write!(s, "<block {size} typeName=\"{ty}\"");
            if let Some(n) = instance {
                let _ = write!(s, " instanceName=\"{n}\"");
            }
            s.push('>');
            point(s, "position", (p.x, p.y));
            s.push_str("<inputVariables>");
            for (k, (formal, _)) in e.inputs.iter().enumerate() {
                let _ = write!(s, "<variable formalParameter=\"{formal}\">");
                input(s, els, at, i, k);
                s.push_str("</variable>");
            }
            s.push_str("</inputVariables><inOutVariables/><outputVariables>");
            for (k, formal) in e.outputs.iter().enumerate() {
                let _ = write!(s, "<variable formalParameter=\"{formal}\">");
                output(s, e, k);
                s.push_str("</variable>");
            }
            s.push_str("</outputVariables></block>");
        }
    }
    s.push('\n');
}

/// The left rail: a connection point at each height a wire leaves it.
fn left_rail(s: &mut String, els: &[Element], at: &Layout) {
    let mut ys: Vec<i32> = Vec::new();
    for i in 0..els.len() {
        for (k, (_, srcs)) in els[i].inputs.iter().enumerate() {
            for &src in srcs.iter().filter(|(id, _)| *id == RAIL) {
                if let Some(&(_, y)) = at.route(els, i, k, src).last() {
                    ys.push(y);
                }
            }
        }
    }
    ys.sort_unstable();
    ys.dedup();
    let top = ys.first().copied().unwrap_or(20) - 20;
    let h = ys.last().copied().unwrap_or(20) + 20 - top;
    let _ = write!(
        s,
        "            <leftPowerRail localId=\"{RAIL}\" height=\"{h}\" width=\"10\">"
    );
    point(s, "position", (20, top));
    for y in ys {
        s.push_str("<connectionPointOut formalParameter=\"\">");
        point(s, "relPosition", (10, y - top));
        s.push_str("</connectionPointOut>");
    }
    s.push_str("</leftPowerRail>\n");
}

/// The right rail: every coil's output, and each function block's ENO, end there.
fn right_rail(s: &mut String, els: &[Element], at: &Layout) {
    let ends: Vec<(u32, Option<&str>, (i32, i32))> = els
        .iter()
        .enumerate()
        .filter(|(_, e)| e.is_output())
        .map(|(i, e)| {
            let formal = matches!(e.kind, Kind::Block { .. }).then_some("ENO");
            let (rx, ry) = out_rel(e, 0);
            (e.id, formal, (at.at[i].x + rx, at.at[i].y + ry))
        })
        .collect();
    let Some(top) = ends.iter().map(|&(_, _, (_, y))| y).min() else {
        return;
    };
    let top = top - 20;
    let bottom = ends.iter().map(|&(_, _, (_, y))| y).max().unwrap_or(top) + 20;
    let id = els.last().map_or(RAIL, |e| e.id) + 1;
    let x = at.right_x;
    let _ = write!(
        s,
        "            <rightPowerRail localId=\"{id}\" height=\"{}\" width=\"10\">",
        bottom - top
    );
    point(s, "position", (x, top));
    for (from, formal, (ox, y)) in ends {
        s.push_str("<connectionPointIn>");
        point(s, "relPosition", (0, y - top));
        connection(s, from, formal, &[(x, y), (ox, y)]);
        s.push_str("</connectionPointIn>");
    }
    s.push_str("</rightPowerRail>\n");
}

/// The LD body: the rails and every element at its place.
pub(super) fn body(els: &[Element]) -> String {
    let at = Layout::new(els);
    let mut s = String::new();
    left_rail(&mut s, els, &at);
    for i in 0..els.len() {
        element(&mut s, els, &at, i);
    }
    right_rail(&mut s, els, &at);
    s
}
