// One uTile's card, laid out as an instrument panel: lamps for the bits (inputs, flip-flops,
// the timers' and counters' outputs, the thresholds), switches for the coils (Y, U, V: a
// click writes), bars for a timer's time left and a counter's count against its preset,
// meters for A6/A7 against their set-points, the scan's figures and the link's health, and
// a trend. Every value carries data-unit, data-signal (the listing's name) and data-value
// (the number it shows, 0/1 for bits); what a user must do is said in words.

import { el, errorText } from "/dom.js";
import { ScanButtons } from "/scan.js";
import { Trend } from "/trend.js";

const HEX = "0123456789ABCDEF";

const range = (n, f) => Array.from({ length: n }, (_, i) => f(i));

// A timer's unit in words: 0.1 s, 1 s, 1 min, 400 s.
export function unitWords(ms) {
  return ms >= 60e3 && ms % 60e3 === 0 ? `${ms / 60e3} min` : `${ms / 1e3} s`;
}

// Time left (tenths of a second) as a panel clock shows it: 4.2 s, 3:05, 1:02:07.
export function clock(tenths) {
  if (tenths < 600) return `${(tenths / 10).toFixed(1)} s`;
  const all = Math.round(tenths / 10);
  const h = Math.floor(all / 3600);
  const m = Math.floor(all / 60) % 60;
  const s = String(all % 60).padStart(2, "0");
  return h ? `${h}:${String(m).padStart(2, "0")}:${s}` : `${m}:${s}`;
}

// A card's state in a word (what the user can do about it comes from the server: `advice`).
const STATE_WORDS = { online: "running", offline: "offline", edit: "EDIT mode", stopped: "not running",
  held: "held" };

export class Card {
  // `unitMs`: each timer's unit in ms, as the core defines it (/api/state's timer_unit_ms);
  // `table`: the signal table (/api/signals) by name, for the ranges the card shows.
  constructor(addr, readOnly, unitMs, table) {
    this.table = table || new Map();
    this.addr = addr;
    this.readOnly = readOnly;
    this.unitMs = unitMs || [];
    this.values = {};
    this.signals = new Map(); // name -> [elements]
    this.root = el("article", { class: "card", "data-unit": addr });
    this.build();
  }

  // An element showing `signal`.
  bind(e, signal) {
    e.dataset.unit = this.addr;
    e.dataset.signal = signal;
    e.dataset.value = "";
    if (!this.signals.has(signal)) this.signals.set(signal, []);
    this.signals.get(signal).push(e);
    return e;
  }

  // A lamp: lit when its bit is 1.
  lamp(signal, label = signal, title = signal) {
    return this.bind(el("span", { class: "lamp", title }, el("i", { class: "led" }), label), signal);
  }

  // A coil's switch: lit when on, a click writes the other value.
  coil(name) {
    const b = this.bind(el("button", { class: "coil", type: "button",
      title: this.readOnly ? `${name} (read-only)` : `${name}: click to switch` },
    el("i", { class: "led" }), name), name);
    if (this.readOnly) b.disabled = true;
    b.addEventListener("click", () => this.write(name, b.dataset.value === "1" ? 0 : 1));
    return b;
  }

  // A preset or set-point field: written on Enter or when it loses focus.
  setting(name, title, cls = "") {
    const i = this.bind(el("input", { class: `setting ${cls}`, inputmode: "numeric", title,
      "aria-label": `${title} (uTile ${this.addr})` }), name);
    if (this.readOnly) i.disabled = true;
    const send = () => {
      if (i.value.trim() === "" || i.value === i.dataset.value) return;
      this.write(name, i.value.trim(), i);
    };
    i.addEventListener("change", send);
    i.addEventListener("keydown", (e) => { if (e.key === "Enter") { send(); i.blur(); } });
    return i;
  }

  // A signal's range as the table gives it: "0..1023".
  range(name) {
    const s = this.table.get(name);
    return s ? `0..${s.max}` : "";
  }

  // A titled group of the panel.
  panel(title, cls, ...children) {
    return el("section", { class: `panel ${cls}` }, el("h3", { text: title }), ...children);
  }

  // A labelled readout; `signal` binds it.
  readout(label, title, signal) {
    const b = el("b", { text: "–" });
    if (signal) this.bind(b, signal);
    return [el("div", { class: "readout", title }, el("span", { text: label }), b), b];
  }

  build() {
    this.stateEl = this.bind(el("span", { class: "state", text: "connecting" }), "online");
    this.root.append(el("header", {}, el("h2", { text: `uTile ${this.addr}` }),
      el("span", { class: "addr", text: `Modbus address ${this.addr}` }), this.stateEl));
    this.adviceEl = el("p", { class: "advice" });
    this.refusal = el("div", { class: "refusal", role: "alert" });
    this.root.append(this.adviceEl, this.refusal);

    const panels = el("div", { class: "panels" });
    this.root.append(panels);
    const row = (tag, title, ...items) => el("div", { class: "bits" }, el("span", { class: "tag", text: tag, title }), ...items);
    panels.append(this.panel("Inputs and outputs", "wide",
      row("PA", "input port PA", ...range(6, (i) => this.lamp(`A${i}`, `A${i}`, `input A${i}`))),
      row("PY", "output port PY: click to switch", ...range(8, (i) => this.coil(`Y${i}`)))));
    panels.append(this.panel("Virtual ports (coils: click to switch)", "wide",
      row("PU", "virtual port PU", ...range(8, (i) => this.coil(`U${i}`))),
      row("PV", "virtual port PV", ...range(8, (i) => this.coil(`V${i}`)))));
    panels.append(this.panel("Flip-flops", "wide", el("div", { class: "bits" },
      ...range(16, (i) => this.lamp(`Q${HEX[i]}`, `Q${HEX[i]}`, `flip-flop Q${HEX[i]}`)))));
    panels.append(this.panel("Analog inputs: reading against the set-point", "wide", this.analog()));
    panels.append(this.panel("Timers: preset × unit, time left", "wide", this.timers()));
    panels.append(this.panel("Counters: count / preset", "wide", this.counters()));
    panels.append(this.panel("Scan", "", this.scan()));
    panels.append(this.panel("Link", "", this.link()));
    this.trend = new Trend(this.addr);
    panels.append(this.panel("Trend", "wide", this.trend.root));
  }

  timers() {
    const grid = el("div", { class: "tiles" });
    this.timerTiles = [];
    for (let m = 0; m < 16; m++) {
      const d = HEX[m];
      const unit = this.unitMs[m] ? unitWords(this.unitMs[m]) : "";
      const fill = el("i");
      const left = el("span", { class: "left", text: "–" });
      const bar = this.bind(el("span", { class: "fillbar", title: `time left on T${d}` }, fill), `TL${d}`);
      bar.fill = fill;
      bar.left = left;
      bar.timer = m;
      const tile = el("div", { class: "tile" },
        el("div", { class: "tile-head" }, this.lamp(`TQ${d}`, `T${d}`, `T${d}'s output (TQ${d})`),
          this.setting(`T${d}`, `timer preset T${d}: ${this.range(`T${d}`)} × ${unit}`, "short"),
          el("span", { class: "unit", text: `× ${unit}` })),
        el("div", { class: "tile-foot" }, bar, left));
      this.timerTiles.push(tile);
      grid.append(tile);
    }
    return grid;
  }

  counters() {
    const grid = el("div", { class: "tiles" });
    this.counterTiles = [];
    for (let m = 0; m < 8; m++) {
      const fill = el("i");
      const tile = el("div", { class: "tile" },
        el("div", { class: "tile-head" }, this.lamp(`CQ${m}`, `C${m}`, `C${m}'s output (CQ${m})`),
          this.bind(el("span", { class: "num", text: "0", title: `count of C${m}` }), `C${m}`),
          el("span", { class: "unit", text: "/" }),
          this.setting(`CP${m}`, `counter preset C${m}: ${this.range(`CP${m}`)} (0: output off)`)),
        el("div", { class: "tile-foot" }, el("span", { class: "fillbar", title: `C${m}: count against preset` }, fill)));
      tile.fill = fill;
      this.counterTiles.push(tile);
      grid.append(tile);
    }
    return grid;
  }

  analog() {
    const box = el("div", { class: "analogs" });
    for (const n of [6, 7]) {
      const fill = el("i");
      const mark = el("b", { title: `set-point S${n}` });
      const volts = el("span", { class: "volts" });
      this[`meter${n}`] = { fill, mark, volts };
      box.append(el("div", { class: "analog" },
        el("span", { class: "name", text: `A${n}` }),
        this.bind(el("span", { class: "num reading", text: "0", title: `reading of A${n}, ${this.range(`A${n}`)}` }), `A${n}`),
        volts,
        el("span", { class: "meter" }, fill, mark),
        el("label", { class: "sp" }, "set-point ", this.setting(`S${n}`, `set-point S${n}: ${this.range(`S${n}`)} (0: threshold off)`)),
        this.lamp(`H${n}`, `H${n}`, `H${n}: A${n} at or over its set-point`)));
    }
    return box;
  }

  scan() {
    this.scanButtons = new ScanButtons(this.addr, this.readOnly, this.refusal);
    const box = el("div", { class: "readouts" }, this.scanButtons.root);
    const add = (...a) => { const [r, b] = this.readout(...a); box.append(r); return b; };
    this.statusEl = add("program", "input register 0: running, watchdog reset, overrun", "status");
    this.scanEl = add("scan µs min / mean / max", "time per scan since RUN, µs");
    this.rateEl = add("scans per second", "scans per second of the uTile's own time");
    add("scans since RUN", "scans since RUN", "scans");
    add("overruns", "received bytes lost since RUN", "overruns");
    return box;
  }

  link() {
    const box = el("div", { class: "readouts" });
    const add = (...a) => { const [r, b] = this.readout(...a); box.append(r); return b; };
    this.refreshEl = add("refreshes per second", "pictures of this uTile per second");
    this.rttEl = add("round trip", "request out to the reply's last byte in, last request");
    this.shareEl = add("share of the line", "share of the line this uTile used over the last two seconds");
    this.reqEl = add("requests", "requests sent to this uTile");
    this.toEl = add("time-outs", "requests with no whole reply in time");
    this.crcEl = add("CRC errors", "replies with a wrong CRC");
    // On a bus every uTile also sets aside the frames for the others and their replies
    // (SPEC §13's count), so the figure grows with the others' traffic: the label says so.
    add("frames set aside (damaged or for another uTile)",
      "Modbus frames the uTile dropped: a wrong CRC, length or gap, or another address; on a bus it grows with the other uTiles' traffic",
      "dropped");
    return box;
  }

  async write(signal, value, input) {
    this.refusal.textContent = "";
    if (input) input.classList.remove("refused");
    let answer;
    try {
      const res = await fetch(`/api/units/${this.addr}/write`, {
        method: "POST",
        headers: { "content-type": "application/json" },
        body: JSON.stringify({ signal, value }),
      });
      if (res.ok) return;
      if (res.status === 401) window.dispatchEvent(new Event("utile-token"));
      answer = { error: await errorText(res) };
    } catch (e) {
      answer = { error: `the server did not answer (${e})` };
    }
    this.refusal.textContent = `${signal} not written: ${answer.error}`;
    if (input) {
      input.classList.add("refused");
      input.value = input.dataset.value;
    }
  }

  update(u) {
    this.values = u.values;
    const v = u.values;
    this.root.dataset.state = u.state;
    this.stateEl.dataset.state = u.state;
    this.stateEl.textContent = STATE_WORDS[u.state] || u.state;
    this.show(this.stateEl, "online", u.online ? 1 : 0);
    this.adviceEl.textContent = u.advice;
    this.scanButtons.update(u);
    for (const [name, els] of this.signals) {
      const value = v[name];
      if (value === undefined) continue;
      for (const e of els) this.show(e, name, value);
    }
    for (const n of [6, 7]) {
      const m = this[`meter${n}`];
      const a = v[`A${n}`] || 0;
      const sp = v[`S${n}`] || 0;
      m.fill.style.width = `${(a / 1023) * 100}%`;
      m.mark.style.left = `${(sp / 1023) * 100}%`;
      m.mark.hidden = !sp;
      m.volts.textContent = `${((a * 5) / 1023).toFixed(2)} V`;
    }
    this.timerTiles.forEach((t, m) => {
      t.classList.toggle("idle", !v[`T${HEX[m]}`] && !v[`TL${HEX[m]}`] && !v[`TQ${HEX[m]}`]);
    });
    this.counterTiles.forEach((t, m) => {
      const count = v[`C${m}`] || 0;
      const preset = v[`CP${m}`] || 0;
      t.fill.style.width = preset ? `${Math.min(100, (count / preset) * 100)}%` : "0";
      t.classList.toggle("idle", !preset && !count);
    });
    if (v.status !== undefined) {
      this.statusEl.textContent = (v.status & 1 ? "running" : "stopped") +
        (v.status & 16 ? ", held" : "") + (v.status & 32 ? ", a hold ended by itself" : "") +
        (v.status & 2 ? ", after a watchdog reset" : "") + (v.status & 8 ? ", overrun" : "");
      this.scanEl.textContent = `${v.scan_min} / ${v.scan_mean} / ${v.scan_max}`;
    }
    this.rateEl.textContent = u.scans_per_s.toLocaleString("en");
    this.refreshEl.textContent = u.refresh_per_s.toFixed(1);
    this.rttEl.textContent = `${u.link.rtt_ms.toFixed(1)} ms`;
    this.shareEl.textContent = `${Math.round(u.link.share * 100)} %`;
    this.reqEl.textContent = u.link.requests.toLocaleString("en");
    this.toEl.textContent = String(u.link.timeouts);
    this.crcEl.textContent = String(u.link.crc_errors);
    if (u.state !== "offline") this.trend.add(v);
  }

  show(e, name, value) {
    e.dataset.value = String(value);
    if (e.tagName === "INPUT") {
      if (document.activeElement !== e && !e.classList.contains("refused")) e.value = String(value);
      return;
    }
    if (e.fill) {
      // Time left, tenths of a second, against the preset's time.
      const d = HEX[e.timer];
      const full = ((this.values[`T${d}`] || 0) * (this.unitMs[e.timer] || 0)) / 100;
      e.fill.style.width = full > 0 ? `${Math.min(100, (value / full) * 100)}%` : "0";
      e.left.textContent = clock(value);
      e.title = `time left on T${d}: ${clock(value)}`;
      return;
    }
    if (e.classList.contains("lamp") || e.classList.contains("coil") || name === "online") return;
    e.textContent = typeof value === "number" && value >= 1e4 ? value.toLocaleString("en") : String(value);
  }
}
