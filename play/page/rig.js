// The test rig of manual §2.4 on the simulated Nano: the LEDs on Y0..Y7 (`data-led`, lit
// with `data-on="1"` while the pin is high), push-buttons A0..A5 (held while the pointer or
// the key is down, or latched with Latch), the A6/A7 levels in volts, the D8/D9 jumpers
// (kept in this browser, as a board keeps its jumpers), reset, power and the EEPROM's erase.
// Every control has `data-rig` (its pin or action) and `data-value` (its state).

import { el } from "./live/dom.js";

// Where the jumpers are kept between visits.
const JUMPERS_KEY = "utile-play-jumpers";
// How long Erase EEPROM waits for its second click.
const ERASE_ARMED_MS = 4000;

// The saved jumpers ({D8, D9} fitted), or none fitted.
function savedJumpers(store) {
  try {
    const saved = JSON.parse(store?.getItem(JUMPERS_KEY) ?? "{}");
    return { D8: saved.D8 === true, D9: saved.D9 === true };
  } catch {
    return { D8: false, D9: false };
  }
}

export class RigPanel {
  // `root`: the panel's element; `nano`: the adapter's Nano; `store`: where the jumpers are
  // kept (localStorage, or null); `notify(text)`: says what happened, in words.
  constructor(root, nano, store, notify) {
    this.nano = nano;
    this.store = store;
    this.notify = notify;
    this.latched = false;
    this.plant = null;
    this.jumpers = savedJumpers(store);
    for (const [pin, fitted] of Object.entries(this.jumpers)) nano.setInput(pin, fitted);

    this.leds = [];
    for (let n = 0; n < 8; n++) {
      const led = el("span", { class: "lamp", "data-led": `Y${n}`, "data-on": "0",
        title: `output Y${n}` }, el("i", { class: "led" }), `Y${n}`);
      this.leds.push(led);
    }
    this.buttons = [];
    for (let n = 0; n < 6; n++) {
      const b = this.control(el("button", { class: "rig-button", type: "button",
        title: `push-button A${n}: hold to press (Latch: click to press, click again to release)` },
      el("i", { class: "led" }), `A${n}`), `A${n}`);
      this.hold(b, `A${n}`);
      this.buttons.push(b);
    }
    this.latch = this.control(el("button", { class: "rig-button latch", type: "button",
      "aria-pressed": "false", title: "latch: a click presses a push-button, the next releases it",
      text: "Latch" }), "latch");
    this.latch.addEventListener("click", () => this.setLatch(!this.latched));
    this.sliders = ["A6", "A7"].map((pin) => this.slider(pin));
    this.jumperButtons = ["D8", "D9"].map((pin) => {
      const what = pin === "D8" ? "autostart at power-up" : "outputs inverted";
      const b = this.control(el("button", { class: "rig-button jumper", type: "button",
        title: `jumper ${pin} (${what}): click to fit or remove; read by the firmware at its start` },
      el("i", { class: "led" }), `${pin} jumper`), pin);
      b.addEventListener("click", () => this.setJumper(pin, !this.jumpers[pin]));
      return b;
    });
    const reset = this.control(el("button", { class: "rig-button reset", type: "button",
      title: "the reset button: a warm start, the program in RAM kept", text: "Reset" }), "reset");
    reset.addEventListener("click", () => nano.reset());
    const power = this.control(el("button", { class: "rig-button", type: "button",
      title: "power off and on: a cold start (RAM cleared; a STOREd program is loaded, and started with D8)",
      text: "Power off/on" }), "power");
    power.addEventListener("click", () => nano.powerCycle());
    this.erase = el("button", { class: "rig-button erase", type: "button", "data-action": "erase-eeprom",
      title: "erase the EEPROM (the STOREd program is lost) and power the Nano off and on: it starts blank",
      text: "Erase EEPROM" });
    this.erase.addEventListener("click", () => this.eraseClicked());
    this.plantBox = el("input", { type: "checkbox", "data-plant": "tank", disabled: "" });
    this.plantBox.addEventListener("change", () => this.setPlant(this.plantBox.checked));
    this.plantLabel = el("label", { class: "plant-option",
      title: "the tank of examples/tank-fill.utl: its level (0..5 V) on A6 and A7 rises 0.4 V/s while the pump Y0 runs, falls 0.2 V/s otherwise" },
    this.plantBox, " Tank on A6/A7, filled by the pump on Y0");

    root.append(
      el("div", { class: "rig-row" }, el("span", { class: "tag", text: "out" }), ...this.leds),
      el("div", { class: "rig-row" }, el("span", { class: "tag", text: "in" }), ...this.buttons, this.latch),
      ...this.sliders.map((s) => s.row),
      el("div", { class: "rig-row" }, el("span", { class: "tag", text: "jmp" }), ...this.jumperButtons),
      el("div", { class: "rig-row" }, this.plantLabel),
      el("div", { class: "rig-row" }, reset, power, this.erase),
    );
    this.show();
  }

  // `e` as the control of `name` (`data-rig`), its state not yet known.
  control(e, name) {
    e.dataset.rig = name;
    e.dataset.value = "0";
    return e;
  }

  // Push-button `pin` on `b`: pressed while held, or toggled by a click when latched.
  hold(b, pin) {
    let down = false;
    const press = () => { down = true; this.press(pin, true); };
    const release = () => { if (down) { down = false; this.press(pin, false); } };
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
      if (this.latched) this.press(pin, !this.nano.inputLow(pin));
    });
  }

  press(pin, low) {
    this.nano.setInput(pin, low);
    this.show();
  }

  setLatch(on) {
    this.latched = on;
    this.latch.setAttribute("aria-pressed", String(on));
    this.latch.dataset.value = on ? "1" : "0";
    // Leaving latch mode lets every latched button go.
    if (!on) for (let n = 0; n < 6; n++) this.nano.setInput(`A${n}`, false);
    this.show();
  }

  // A6 or A7's slider and its volts.
  slider(pin) {
    const input = this.control(el("input", { class: "rig-level", type: "range", min: "0", max: "5",
      step: "0.05", value: "0", "aria-label": `${pin} level, volts` }), pin);
    const volts = el("b", { class: "rig-volts", text: "0.00 V" });
    input.addEventListener("input", () => {
      this.nano.setVolts(pin, Number(input.value));
      this.show();
    });
    const row = el("label", { class: "rig-analog" }, el("span", { class: "name", text: pin }), input, volts);
    return { pin, input, volts, row };
  }

  setJumper(pin, fitted) {
    this.jumpers[pin] = fitted;
    this.nano.setInput(pin, fitted);
    try {
      this.store?.setItem(JUMPERS_KEY, JSON.stringify(this.jumpers));
    } catch {
      // Storage refused: the jumper still works for this visit.
    }
    this.show();
  }

  // The first click arms the erase, a second within a few seconds erases.
  eraseClicked() {
    if (this.erase.dataset.armed !== "1") {
      this.erase.dataset.armed = "1";
      this.erase.textContent = "Erase EEPROM: click again";
      clearTimeout(this.disarm);
      this.disarm = setTimeout(() => this.disarmErase(), ERASE_ARMED_MS);
      return;
    }
    this.disarmErase();
    this.nano.eraseEeprom();
    this.nano.powerCycle();
    this.notify("EEPROM erased; the Nano was powered off and on: it starts blank.");
  }

  disarmErase() {
    clearTimeout(this.disarm);
    delete this.erase.dataset.armed;
    this.erase.textContent = "Erase EEPROM";
  }

  // `plant`: the page's plant (plant.js), once the WebAssembly module is there.
  attachPlant(plant) {
    this.plant = plant;
    this.plantBox.disabled = false;
  }

  setPlant(on) {
    if (!this.plant) return;
    const why = on ? this.plant.start("tank") : (this.plant.stop(), null);
    if (why) {
      this.plantBox.checked = false;
      this.notify(`The tank cannot start: ${why}`);
    }
    this.plantBox.dataset.value = this.plant.running ? "1" : "0";
  }

  // The Nano's pins and the rig's state on the controls (after every frame; an element is
  // touched only when what it shows changes).
  show() {
    const y = this.nano.y;
    this.leds.forEach((led, n) => put(led, "on", (y >> n) & 1 ? "1" : "0"));
    this.buttons.forEach((b, n) => put(b, "value", this.nano.inputLow(`A${n}`) ? "1" : "0"));
    for (const b of this.jumperButtons) {
      const fitted = this.nano.inputLow(b.dataset.rig) ? "1" : "0";
      if (put(b, "value", fitted)) b.setAttribute("aria-pressed", String(fitted === "1"));
    }
    for (const { pin, input, volts } of this.sliders) {
      const v = this.nano.volts[pin].toFixed(2);
      if (put(input, "value", v)) volts.textContent = `${v} V`;
      if (document.activeElement !== input && input.value !== String(this.nano.volts[pin])) {
        input.value = String(this.nano.volts[pin]);
      }
    }
  }
}

// Sets `e.dataset[key]` to `value` if it is not that already; whether it changed.
function put(e, key, value) {
  if (e.dataset[key] === value) return false;
  e.dataset[key] = value;
  return true;
}
