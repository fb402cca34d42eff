// The virtual Nano's rig on a card (utile live --rig): push-buttons A0..A5 (held while the
// pointer or the key is down, or latched with Latch), the A6/A7 levels in volts, the D8/D9
// jumpers and reset. Each posts the control socket's own JSON to /api/units/N/rig. The panel
// shows only while /api/state's `rig` says a rig answers and has a Nano for the card: a single
// Nano's rig is on every card; on a bus (`cargo nano --bus N`) card N works Nano N, the one at
// its slave address. Read-only, its controls are disabled. A panel's requests go one at a
// time, in the order they were made: a release never overtakes its press.

import { el, errorText } from "/dom.js";

// POSTs `request` for uTile `addr`: `{state}`, the rig's state after it, or `{why}`, the
// server's words when it refuses.
export async function rigRequest(addr, request) {
  try {
    const res = await fetch(`/api/units/${addr}/rig`, {
      method: "POST",
      headers: { "content-type": "application/json" },
      body: JSON.stringify(request),
    });
    return res.ok ? { state: await res.json() } : { why: await errorText(res) };
  } catch (e) {
    return { why: `the server did not answer (${e})` };
  }
}

// The state of the Nano that uTile `addr`'s card works (as RigView::nano_of in rig.rs): the
// only one, or on a bus the one at that address; null when the rig has none there.
function nanoOf(rig, addr) {
  if (rig.nanos.length === 1) return rig.nanos[0];
  return rig.nanos[addr - 1] || null;
}

export class RigPanel {
  // `refusal`: the card's element for a refusal in words.
  constructor(addr, readOnly, refusal) {
    this.addr = addr;
    this.readOnly = readOnly;
    this.refusal = refusal;
    this.latched = false;
    // The last request under way: the next waits for its answer.
    this.queue = Promise.resolve();
    this.controls = [];
    const control = (e, name) => {
      e.dataset.rig = name;
      e.dataset.unit = addr;
      e.dataset.value = "";
      if (readOnly) e.disabled = true;
      this.controls.push(e);
      return e;
    };
    this.switches = [];
    for (let n = 0; n < 6; n++) {
      const b = control(el("button", { class: "rig-button", type: "button",
        title: `switch A${n}: hold to press (Latch: click to press, click again to release)` },
      el("i", { class: "led" }), `A${n}`), `A${n}`);
      this.hold(b, n);
      this.switches.push(b);
    }
    this.latch = control(el("button", { class: "rig-button latch", type: "button",
      "aria-pressed": "false", title: "latch: a click presses a switch, the next releases it",
      text: "Latch" }), "latch");
    this.latch.addEventListener("click", () => {
      this.latched = !this.latched;
      this.latch.setAttribute("aria-pressed", String(this.latched));
      this.latch.dataset.value = this.latched ? "1" : "0";
    });
    this.sliders = [6, 7].map((n) => {
      const input = control(el("input", { class: "rig-level", type: "range", min: "0", max: "5",
        step: "0.05", "aria-label": `A${n} level, volts (uTile ${addr})` }), `A${n}`);
      const volts = el("b", { class: "rig-volts", text: "– V" });
      this.level(input, volts, n);
      return { input, volts, row: el("label", { class: "rig-analog" },
        el("span", { class: "name", text: `A${n}` }), input, volts) };
    });
    this.jumpers = ["d8", "d9"].map((j) => {
      const b = control(el("button", { class: "rig-button jumper", type: "button",
        title: `jumper ${j.toUpperCase()}: click to fit or remove` },
      el("i", { class: "led" }), j.toUpperCase()), j.toUpperCase());
      b.addEventListener("click", () => this.send({ [j]: b.dataset.value !== "1" }));
      return b;
    });
    const reset = control(el("button", { class: "rig-button reset", type: "button",
      title: "reset the Nano (warm, as the rig's r key)", text: "Reset" }), "reset");
    reset.addEventListener("click", () => this.send({ reset: true }));
    this.why = el("span", { class: "scan-why" });
    if (readOnly) this.why.textContent = "read-only: the rig is refused";
    this.root = el("section", { class: "panel wide rig", hidden: "" },
      el("h3", { text: "Virtual rig: switches, levels, jumpers" }),
      el("div", { class: "bits" }, ...this.switches, this.latch),
      ...this.sliders.map((s) => s.row),
      el("div", { class: "bits" }, ...this.jumpers, reset, this.why));
  }

  // Switch `n` on button `b`: pressed while held, or toggled when latched.
  hold(b, n) {
    let down = false;
    const press = () => { down = true; this.send({ press: n }); };
    const release = () => { if (down) { down = false; this.send({ release: n }); } };
    b.addEventListener("pointerdown", (e) => {
      if (this.latched || e.button !== 0) return;
      b.setPointerCapture(e.pointerId);
      press();
    });
    b.addEventListener("pointerup", release);
    b.addEventListener("pointercancel", release);
    b.addEventListener("keydown", (e) => {
      if ((e.key === " " || e.key === "Enter") && !e.repeat && !this.latched) { e.preventDefault(); press(); }
    });
    b.addEventListener("keyup", (e) => { if (e.key === " " || e.key === "Enter") release(); });
    b.addEventListener("click", () => {
      if (this.latched) this.send(b.dataset.value === "1" ? { release: n } : { press: n });
    });
  }

  // A6/A7's slider: sent as it moves (one request at a time, the latest wins). The value
  // sent is the one the user set, taken at its event: while a request is out, the state's
  // events may still carry the level from before and show() would put it back on the slider.
  level(input, volts, n) {
    let busy = false;
    let again = false;
    let want = 0;
    const key = `a${n}`;
    const go = async () => {
      want = Number(input.value);
      if (busy) { again = true; return; }
      busy = true;
      input.dataset.sending = "1";
      do {
        again = false;
        const v = want;
        volts.textContent = `${v.toFixed(2)} V`;
        await this.send({ [key]: v });
      } while (again);
      busy = false;
      delete input.dataset.sending;
    };
    input.addEventListener("input", go);
    input.addEventListener("change", go);
    input.addEventListener("pointerdown", () => { input.dataset.moving = "1"; });
    input.addEventListener("pointerup", () => { delete input.dataset.moving; });
  }

  // Sends `request` once the panel's requests before it are answered (two fetches at once
  // may reach the server in either order); the rig's answer shows at once (the state's
  // events follow).
  send(request) {
    const turn = this.queue.then(async () => {
      this.refusal.textContent = "";
      const { state, why } = await rigRequest(this.addr, request);
      if (why) this.refusal.textContent = `rig refused: ${why}`;
      else this.show(state);
    });
    this.queue = turn.catch(() => {});
    return turn;
  }

  // `rig`: /api/state's `rig` (null without --rig).
  update(rig) {
    const s = rig && rig.connected ? nanoOf(rig, this.addr) : null;
    this.root.hidden = !s;
    if (s) this.show(s);
  }

  // The rig's state `s` on the controls.
  show(s) {
    this.switches.forEach((b, n) => { b.dataset.value = s.switches[n] ? "1" : "0"; });
    this.jumpers[0].dataset.value = s.d8 ? "1" : "0";
    this.jumpers[1].dataset.value = s.d9 ? "1" : "0";
    this.sliders.forEach(({ input, volts }, i) => {
      const v = i === 0 ? s.a6 : s.a7;
      input.dataset.value = v.toFixed(2);
      if (input.dataset.moving || input.dataset.sending || document.activeElement === input) return;
      input.value = String(v);
      volts.textContent = `${v.toFixed(2)} V`;
    });
  }
}
