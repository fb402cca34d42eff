// The Ladder tab: the program a uTile runs, drawn as rungs by the kit's drawer (the SVG of
// GET /api/units/N/ladder, fetched once per program and again when a preset changes), lit
// with the power flow of every picture from the line values the events already bring
// (`program.values`, the core's engine run the Program tab shows). Each element and wire of
// the drawing names in `data-power-lines` the lines whose values, ANDed, are its power; here
// it gets data-powered = 1, 0 or ? (docs/LADDER.md, "Power flow"), a contact also
// data-closed (the value its own lines leave) and data-power-in (the power at its left), and
// an instruction block's line its value.
// A refresh only sets the attributes that change: nothing is drawn again.

import { el, errorText } from "/dom.js";

const HEX = "0123456789ABCDEF";
const SVG_NS = "http://www.w3.org/2000/svg";
// Redraw measures since they were last cleared.
let measures = 0;

// The lines of a comma-separated list, as numbers.
const numbers = (list) => (list ? list.split(",").map(Number) : []);

// The values of `lines` ANDed: 0 if any is 0, else ? if any is not 1 (?, or not reached),
// else 1 (no lines: the left rail).
function and(values, lines) {
  let p = "1";
  for (const l of lines) {
    const v = values[l];
    if (v === "0") return "0";
    if (v !== "1") p = "?";
  }
  return p;
}

// What the drawing depends on besides the program: the presets drawn on the TOF and CTU coils.
function presetKey(v) {
  let key = "";
  for (let m = 0; m < 16; m++) key += `${v[`T${HEX[m]}`]},`;
  for (let m = 0; m < 8; m++) key += `${v[`CP${m}`]},`;
  return key;
}

export class LadderView {
  constructor(addr) {
    this.addr = addr;
    this.key = null;
    this.loading = false;
    this.items = [];
    this.rungs = [];
    this.values = "";
    this.last = null;
    this.note = el("div", { class: "hint", text: "waiting for the program…" });
    this.box = el("div", { class: "ladder-box", "data-unit": addr });
    this.root = el("div", { class: "ladder-view", "data-unit": addr },
      el("h2", { text: `uTile ${addr}` }), this.note, this.box);
  }

  // The drawing of the program with fingerprint `fingerprint`, made ready to light.
  async load(key, fingerprint) {
    this.key = key;
    this.loading = true;
    let res;
    try {
      res = await fetch(`/api/units/${this.addr}/ladder`);
    } catch (e) {
      res = null;
    }
    this.loading = false;
    if (!res || !res.ok) {
      this.key = null;
      this.note.textContent = `the ladder cannot be shown: ${res ? await errorText(res) : "the server did not answer"}`;
      this.note.dataset.error = "1";
      return;
    }
    delete this.note.dataset.error;
    const doc = await res.json();
    // The program changed while it was drawn: the next picture asks again.
    if (doc.fingerprint !== fingerprint) this.key = null;
    const parsed = new DOMParser().parseFromString(doc.svg, "image/svg+xml");
    const svg = document.importNode(parsed.documentElement, true);
    // The drawing's own style is for a white sheet and would reach the whole page: the
    // page's stylesheet draws it instead.
    for (const s of svg.querySelectorAll("style")) s.remove();
    this.items = [];
    for (const e of svg.querySelectorAll("[data-power-lines]")) {
      e.setAttribute("data-unit", this.addr);
      e.setAttribute("data-powered", "");
      const item = { e, lines: numbers(e.getAttribute("data-power-lines")), powered: "" };
      const cls = e.getAttribute("class");
      if (cls === "contact") {
        const own = numbers(e.getAttribute("data-lines"));
        item.closedLine = own[own.length - 1];
        item.closed = "";
        item.inLines = item.lines.slice(0, -1);
        item.in = "";
      }
      if (cls === "line") {
        // An instruction block's line shows its value after its text.
        item.text = document.createElementNS(SVG_NS, "tspan");
        item.text.setAttribute("class", "value");
        e.append(" ", item.text);
      }
      this.items.push(item);
    }
    this.rungs = [...svg.querySelectorAll("g.rung")].map((g) => {
      g.setAttribute("data-unit", this.addr);
      return { g, first: numbers(g.getAttribute("data-lines"))[0], reached: "" };
    });
    this.box.replaceChildren(svg);
    this.note.textContent = doc.consistent ? "" : "the lines read do not give the program's fingerprint: reading them again";
    this.values = "";
    if (this.last) this.light(this.last);
  }

  update(u) {
    if (u.legacy) {
      this.note.textContent = "this uTile's firmware does not serve its program (SPEC §17): update it";
      return;
    }
    const p = u.program;
    if (!p) return;
    const key = `${p.fingerprint} ${presetKey(u.values)}`;
    if (key !== this.key && !this.loading) this.load(key, p.fingerprint);
    this.last = p.values;
    // Hidden, nothing to light: showing the tab lights it (refresh).
    if (!this.root.parentElement || this.root.parentElement.hidden) return;
    this.light(p.values);
  }

  // The tab shown: light the drawing from the latest values.
  refresh() {
    if (this.last) this.light(this.last);
  }

  // Sets data-powered (and data-closed, a block line's value) where they change; then the
  // browser's style and layout for them, measured as "ladder-redraw" (BENCHMARKS.md).
  light(values) {
    if (values === this.values || !this.items.length) return;
    const start = performance.now();
    this.values = values;
    for (const it of this.items) {
      const p = and(values, it.lines);
      if (p !== it.powered) {
        it.powered = p;
        it.e.setAttribute("data-powered", p);
        if (it.text) it.text.textContent = `→ ${p}`;
      }
      if (it.closedLine !== undefined) {
        const c = and(values, [it.closedLine]);
        if (c !== it.closed) {
          it.closed = c;
          it.e.setAttribute("data-closed", c);
        }
        const i = and(values, it.inLines);
        if (i !== it.in) {
          it.in = i;
          it.e.setAttribute("data-power-in", i);
        }
      }
    }
    for (const r of this.rungs) {
      const reached = (values[r.first] || " ") !== " " ? "1" : "0";
      if (reached !== r.reached) {
        r.reached = reached;
        r.g.setAttribute("data-reached", reached);
      }
    }
    // Style and layout now, so the measure holds what this refresh costs the browser.
    this.box.getBoundingClientRect();
    performance.measure("ladder-redraw", { start, end: performance.now(), detail: this.addr });
    // The browser keeps every measure: a page open for days keeps the last thousand.
    if (++measures >= 1000) {
      performance.clearMeasures("ladder-redraw");
      measures = 0;
    }
  }
}
