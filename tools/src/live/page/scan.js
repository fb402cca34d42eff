// Run, Hold and Step (SPEC §18) for one card: each button posts to /api/units/N/scan. They
// are disabled, with the reason beside them, when the page is read-only or the uTile's
// firmware cannot hold its scan (the server's words); the card's state says "held".
// The page names itself (PAGE) in its requests and in its events (app.js): a hold it makes
// lives while it follows the events, and ends 10 s after it closed.

import { el, errorText } from "/dom.js";

// This page's name for itself: random, made once per load (getRandomValues works on plain
// http beyond loopback too).
export const PAGE = Array.from(crypto.getRandomValues(new Uint8Array(12)),
  (b) => b.toString(16).padStart(2, "0")).join("");

// POSTs `{action, n, page}` for uTile `addr`; the server's words when it refuses, else "".
export async function scanAction(addr, action, n) {
  try {
    const body = n ? { action, n, page: PAGE } : { action, page: PAGE };
    const res = await fetch(`/api/units/${addr}/scan`, {
      method: "POST",
      headers: { "content-type": "application/json" },
      body: JSON.stringify(body),
    });
    return res.ok ? "" : await errorText(res);
  } catch (e) {
    return `the server did not answer (${e})`;
  }
}

export class ScanButtons {
  // `refusal`: the card's element for a refusal in words.
  constructor(addr, readOnly, refusal) {
    this.addr = addr;
    this.readOnly = readOnly;
    this.refusal = refusal;
    const button = (action, label, title, steps) => {
      const b = el("button", { class: "scan-button", type: "button", "data-action": action,
        "data-unit": addr, title, text: label });
      if (steps) b.dataset.steps = String(steps);
      b.addEventListener("click", () => this.act(action, steps));
      return b;
    };
    this.buttons = [
      button("run", "Run", "let the scan run freely (holding register 32 = 0)"),
      button("hold", "Hold", "hold the scan at its next END (holding register 32 = 1)"),
      button("step", "Step 1", "run exactly one scan, then hold (holding register 33 = 1)", 1),
      button("step", "Step 10", "run exactly ten scans, then hold (holding register 33 = 10)", 10),
    ];
    this.why = el("span", { class: "scan-why" });
    this.root = el("div", { class: "scan-control" }, ...this.buttons, this.why);
    this.update(null);
  }

  async act(action, steps) {
    this.refusal.textContent = "";
    const why = await scanAction(this.addr, action, steps);
    if (why) this.refusal.textContent = `${action} refused: ${why}`;
  }

  // `u`: the unit's part of /api/state (null before the first).
  update(u) {
    let why = "";
    if (this.readOnly) why = "read-only: hold and step are refused";
    else if (u && u.scan_control && u.scan_control.why) why = u.scan_control.why;
    const off = why !== "" || !u || u.state === "offline" || u.state === "edit";
    for (const b of this.buttons) b.disabled = off;
    this.why.textContent = why;
    const held = u && u.state === "held";
    this.root.dataset.held = held ? "1" : "0";
  }
}
