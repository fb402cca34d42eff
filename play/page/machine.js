// The Nano's clock: the simulated Nano run in step with the wall clock, a batch of simulated
// time each animation frame (as much as the wall clock moved since the last one), in slices
// after each of which the serial port, the plant and the outputs are served. Paused while
// the tab is hidden (no animation frames then; back in view it goes on from there, it does
// not catch up). Unpaced (`?speed=max`), each frame runs as long as it can and still lets the
// page draw: the speed figure then says how fast this browser runs the firmware.

import { CYCLES_PER_MS } from "./sim/nano.js";

// Simulated time of one slice at most: the serial port and the plant see the chip this often.
const SLICE_MS = 5;
// A frame never runs more than this much simulated time (a stalled page, a slow machine).
const MAX_FRAME_MS = 100;
// Unpaced: the wall-clock time a frame works before the page draws.
const UNPACED_WORK_MS = 14;
// The speed figure covers the frames of about the last second.
const SPEED_WINDOW_MS = 1000;
// The figure on the page changes this often.
const SHOW_EVERY_MS = 250;

export class Machine {
  // `nano`: the adapter's Nano; `unpaced`: run as fast as the browser can.
  constructor(nano, { unpaced = false } = {}) {
    this.nano = nano;
    this.unpaced = unpaced;
    this.sliceHooks = [];
    this.frameHooks = [];
    this.errorHooks = [];
    // The wall-clock time of the last frame (null: the clock starts at the next one).
    this.last = null;
    this.running = false;
    // Recent frames: [wall ms, simulated ms] each, for the speed figure.
    this.recent = [];
    this.shown = 0;
    // Simulated × real time over the recent frames.
    this.speed = 0;
  }

  // `f(changes)` after each slice, with the outputs' changes in it ({pin, level, cycle}).
  onSlice(f) {
    this.sliceHooks.push(f);
  }

  // `f()` after each frame's batch.
  onFrame(f) {
    this.frameHooks.push(f);
  }

  // `f(error)` when the simulation stops on an error.
  onError(f) {
    this.errorHooks.push(f);
  }

  start() {
    this.running = true;
    document.addEventListener("visibilitychange", () => {
      // Hidden: the frames stop. Back: the clock starts again from the next frame.
      this.last = null;
      if (!document.hidden) this.schedule();
    });
    this.schedule();
  }

  schedule() {
    if (this.running && !document.hidden) requestAnimationFrame((t) => this.frame(t));
  }

  frame(now) {
    if (!this.running) return;
    if (this.last === null) {
      this.last = now;
      this.schedule();
      return;
    }
    const wall = now - this.last;
    this.last = now;
    const before = this.nano.cycles;
    try {
      if (this.unpaced) {
        const t0 = performance.now();
        while (performance.now() - t0 < UNPACED_WORK_MS) this.slice(this.nano.cycles + SLICE_MS * CYCLES_PER_MS);
      } else {
        const end = before + Math.round(Math.min(wall, MAX_FRAME_MS) * CYCLES_PER_MS);
        while (this.nano.cycles < end) this.slice(Math.min(end, this.nano.cycles + SLICE_MS * CYCLES_PER_MS));
      }
    } catch (e) {
      this.running = false;
      for (const f of this.errorHooks) f(e);
      return;
    }
    this.measure(now, wall, (this.nano.cycles - before) / CYCLES_PER_MS);
    for (const f of this.frameHooks) f();
    this.schedule();
  }

  // Runs the chip to cycle `end` and serves the hooks.
  slice(end) {
    this.nano.runUntil(end);
    const changes = this.nano.takePinChanges();
    for (const f of this.sliceHooks) f(changes);
  }

  // The speed over the recent frames, shown on [data-sim-speed] now and then.
  measure(now, wall, simulated) {
    this.recent.push([now, wall, simulated]);
    while (this.recent.length > 1 && now - this.recent[0][0] > SPEED_WINDOW_MS) this.recent.shift();
    let w = 0;
    let s = 0;
    for (const [, dw, ds] of this.recent) {
      w += dw;
      s += ds;
    }
    this.speed = w > 0 ? s / w : 0;
    if (now - this.shown < SHOW_EVERY_MS) return;
    this.shown = now;
    for (const e of document.querySelectorAll("[data-sim-speed]")) {
      e.dataset.value = this.speed.toFixed(2);
      e.textContent = `${this.speed.toFixed(2)}× real time`;
    }
    const up = document.getElementById("uptime");
    if (up) {
      const secs = Math.floor(this.nano.ms / 1000);
      up.textContent = `${Math.floor(secs / 60)}:${String(secs % 60).padStart(2, "0")}`;
    }
  }
}
