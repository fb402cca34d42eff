// One uTile's card: inputs, outputs and the virtual ports (click a coil to write it),
// flip-flops, timers (preset, running, time left as a bar), counters (count against preset),
// A6/A7 (reading, set-point, threshold bit), the scan figures and the link's health. Every
// value carries data-unit, data-signal (the listing's name) and data-value.

import { Trend } from "/trend.js";

const HEX = "0123456789ABCDEF";
// Timer units in ms (T0..T3 0.1 s, T4..TB 1 s, TC..TE 1 min, TF 400 s): a preset times this.
const UNIT_MS = [100, 100, 100, 100, 1e3, 1e3, 1e3, 1e3, 1e3, 1e3, 1e3, 1e3, 6e4, 6e4, 6e4, 4e5];

function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "class") e.className = v;
    else if (k === "text") e.textContent = v;
    else e.setAttribute(k, v);
  }
  e.append(...children);
  return e;
}

export class Card {
  constructor(addr, readOnly) {
    this.addr = addr;
    this.readOnly = readOnly;
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

  lamp(name) {
    return this.bind(el("span", { class: "lamp", text: name, title: name }), name);
  }

  coil(name) {
    const b = this.bind(el("button", { class: "coil", text: name, type: "button",
      title: `${name}: click to switch` }), name);
    if (this.readOnly) b.disabled = true;
    b.addEventListener("click", () => this.write(name, b.dataset.value === "1" ? 0 : 1));
    return b;
  }

  setting(name, title) {
    const i = this.bind(el("input", { class: "setting", inputmode: "numeric", title,
      "aria-label": `${name} of uTile ${this.addr}` }), name);
    if (this.readOnly) i.disabled = true;
    const send = () => {
      if (i.value.trim() === "" || i.value === i.dataset.value) return;
      this.write(name, i.value.trim(), i);
    };
    i.addEventListener("change", send);
    i.addEventListener("keydown", (e) => { if (e.key === "Enter") { send(); i.blur(); } });
    return i;
  }

  row(label, ...items) {
    return el("div", { class: "row" }, el("span", { class: "label", text: label }), ...items);
  }

  build() {
    const r = this.root;
    this.stateEl = this.bind(el("span", { class: "state", text: "…" }), "online");
    this.reasonEl = el("span", { class: "reason" });
    r.append(el("header", {}, el("h2", { text: `uTile ${this.addr}` }), this.stateEl, this.reasonEl));

    const range = (n, f) => Array.from({ length: n }, (_, i) => f(i));
    r.append(this.row("inputs", ...range(6, (i) => this.lamp(`A${i}`))));
    r.append(this.row("outputs", ...range(8, (i) => this.coil(`Y${i}`))));
    r.append(this.row("U", ...range(8, (i) => this.coil(`U${i}`))));
    r.append(this.row("V", ...range(8, (i) => this.coil(`V${i}`))));
    r.append(this.row("flip-flops", ...range(16, (i) => this.lamp(`Q${HEX[i]}`))));

    // Timers: preset, TQ and the time left as a bar of the preset's time.
    const timers = el("div", { class: "grid" });
    for (let m = 0; m < 16; m++) {
      const d = HEX[m];
      const bar = el("i");
      const tl = this.bind(el("span", { class: "tbar", title: `time left on T${d}` }, bar), `TL${d}`);
      tl.bar = bar;
      tl.timer = m;
      timers.append(el("div", { class: "cell" },
        this.bind(el("span", { class: "name lamp", text: `T${d}` }), `TQ${d}`),
        this.setting(`T${d}`, `timer preset T${d}: 0..255 × ${UNIT_MS[m] >= 6e4 ? UNIT_MS[m] / 6e4 + " min" : UNIT_MS[m] / 1e3 + " s"}`),
        tl));
    }
    r.append(el("div", { class: "row" }, el("span", { class: "label", text: "timers" })), timers);

    // Counters: count / preset, CQ.
    const counters = el("div", { class: "grid" });
    for (let m = 0; m < 8; m++) {
      counters.append(el("div", { class: "cell" },
        this.bind(el("span", { class: "name lamp", text: `C${m}` }), `CQ${m}`),
        this.bind(el("span", { class: "num", text: "0" }), `C${m}`),
        el("span", { text: "/" }),
        this.setting(`CP${m}`, `counter preset C${m}: 0..65535 (0: output off)`)));
    }
    r.append(el("div", { class: "row" }, el("span", { class: "label", text: "counters" })), counters);

    // Analog inputs: reading against the set-point, threshold bit.
    for (const n of [6, 7]) {
      const fill = el("i");
      const mark = el("b");
      const meter = el("span", { class: "meter" }, fill, mark);
      this[`meter${n}`] = { fill, mark };
      r.append(el("div", { class: "analog" },
        el("span", { class: "name", text: `A${n}` }),
        this.bind(el("span", { class: "num", text: "0", title: `reading of A${n}, 0..1023` }), `A${n}`),
        meter,
        el("span", { text: "set-point" }),
        this.setting(`S${n}`, `set-point S${n}: 0..1023 (0: threshold off)`),
        this.lamp(`H${n}`)));
    }

    const stat = (label, signal, title) => {
      const b = signal ? this.bind(el("b", { text: "–" }), signal) : el("b", { text: "–" });
      const s = el("span", { title: title || label }, `${label} `, b);
      return [s, b];
    };
    const stats = el("div", { class: "stats" });
    const add = (...a) => { const [s, b] = stat(...a); stats.append(s); return b; };
    this.statusEl = add("status", "status", "input register 0: bit 0 running, 1 watchdog reset, 2 stored program, 3 overrun");
    this.scanEl = add("scan µs min/mean/max", null);
    add("scans", "scans", "scans since RUN");
    this.rateEl = add("scans/s", null);
    add("overruns", "overruns", "received bytes lost since RUN");
    add("dropped frames", "dropped", "Modbus frames the uTile dropped (CRC, length, gap)");
    this.refreshEl = add("refresh/s", null, "pictures of this uTile per second");
    this.rttEl = add("round trip", null, "request out to the reply's last byte in, last request");
    this.shareEl = add("line share", null, "share of the line this uTile used over the last two seconds");
    this.reqEl = add("requests", null);
    this.toEl = add("time-outs", null);
    this.crcEl = add("CRC errors", null);
    r.append(stats);
    this.refusal = el("div", { class: "refusal", role: "alert" });
    r.append(this.refusal);
    this.trend = new Trend(this.addr);
    r.append(this.trend.root);
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
      answer = await res.json();
      if (res.ok) return;
    } catch (e) {
      answer = { error: `the server did not answer (${e})` };
    }
    this.refusal.textContent = answer.error;
    if (input) {
      input.classList.add("refused");
      input.value = input.dataset.value;
    }
  }

  update(u) {
    this.values = u.values;
    const offline = u.state === "offline";
    this.root.classList.toggle("offline", offline);
    this.stateEl.dataset.state = u.state;
    this.stateEl.textContent = { online: "online", offline: "offline", edit: "EDIT mode",
      stopped: "not running" }[u.state] || u.state;
    this.reasonEl.textContent = u.reason || "";
    const v = u.values;
    for (const [name, els] of this.signals) {
      const value = v[name];
      if (value === undefined) continue;
      for (const e of els) this.show(e, name, value);
    }
    for (const n of [6, 7]) {
      const m = this[`meter${n}`];
      m.fill.style.width = `${((v[`A${n}`] || 0) / 1023) * 100}%`;
      m.mark.style.left = `${((v[`S${n}`] || 0) / 1023) * 100}%`;
      m.mark.hidden = !v[`S${n}`];
    }
    if (v.status !== undefined) {
      this.statusEl.textContent = (v.status & 1 ? "running" : "stopped") +
        (v.status & 2 ? ", watchdog reset" : "") + (v.status & 8 ? ", overrun" : "");
      this.scanEl.textContent = `${v.scan_min}/${v.scan_mean}/${v.scan_max}`;
    }
    this.rateEl.textContent = String(u.scans_per_s);
    this.refreshEl.textContent = u.refresh_per_s.toFixed(1);
    this.rttEl.textContent = `${u.link.rtt_ms.toFixed(1)} ms`;
    this.shareEl.textContent = `${Math.round(u.link.share * 100)} %`;
    this.reqEl.textContent = String(u.link.requests);
    this.toEl.textContent = String(u.link.timeouts);
    this.crcEl.textContent = String(u.link.crc_errors);
    if (!offline) this.trend.add(v);
  }

  show(e, name, value) {
    e.dataset.value = String(value);
    if (e.tagName === "INPUT") {
      if (document.activeElement !== e && !e.classList.contains("refused")) e.value = String(value);
      return;
    }
    if (e.bar) {
      // Time left, tenths of a second, against the preset's time.
      const preset = this.values[`T${HEX[e.timer]}`] || 0;
      const full = (preset * UNIT_MS[e.timer]) / 100;
      e.bar.style.width = full > 0 ? `${Math.min(100, (value / full) * 100)}%` : "0";
      e.title = `time left on T${HEX[e.timer]}: ${(value / 10).toFixed(1)} s`;
      return;
    }
    if (e.classList.contains("lamp") || e.classList.contains("coil")) return;
    if (name === "online") return;
    e.textContent = String(value);
  }
}
