// The program, live: the listing the uTile runs (read over Modbus, SPEC §17) with each line's
// value from the latest picture: the bit on top of the stack after the line, or for a line
// that pops (`.Y0` …) the bit it took (shown with an arrow); `?` where the picture cannot
// tell (edges, toggles, clocks). With --program FILE, whether that listing is the one that runs.

import { el, errorText } from "/dom.js";

export class ProgramView {
  constructor(addr) {
    this.addr = addr;
    this.fingerprint = null;
    this.cells = [];
    this.check = el("div", { class: "check" });
    this.table = el("table", { class: "listing" });
    this.note = el("div", { class: "hint", text: "waiting for the program…" });
    this.root = el("div", { class: "program", "data-unit": addr },
      el("h2", { text: `uTile ${addr}` }), this.check, this.note, this.table);
  }

  async load(fingerprint) {
    this.fingerprint = fingerprint;
    const res = await fetch(`/api/units/${this.addr}/program`);
    if (!res.ok) {
      this.fingerprint = null;
      this.note.textContent = `the program cannot be shown: ${await errorText(res)}`;
      this.note.dataset.error = "1";
      return;
    }
    delete this.note.dataset.error;
    const p = await res.json();
    this.table.replaceChildren();
    this.cells = [];
    for (const line of p.lines) {
      const v = el("td", { class: "v", "data-unit": this.addr, "data-line": line.n, "data-value": "" });
      v.pops = line.pops;
      this.cells[line.n] = v;
      this.table.append(el("tr", { "data-line": line.n },
        el("td", { class: "n", text: String(line.n).padStart(3, "0") }),
        el("td", { class: "op", text: line.name }), v));
    }
    this.note.textContent = p.lines.length ? "" : "the program is empty";
  }

  update(u) {
    const p = u.program;
    if (u.legacy) {
      this.note.textContent = "this uTile's firmware does not serve its program (SPEC §17): update it";
      return;
    }
    if (!p) return;
    if (p.fingerprint !== this.fingerprint) this.load(p.fingerprint);
    const file = p.file;
    if (file) {
      this.check.textContent = file.matches
        ? `runs ${file.name} (fingerprint ${hex(p.fingerprint)})`
        : `does NOT run ${file.name}: fingerprint ${hex(p.fingerprint)}, the file's ${hex(file.fingerprint)}`;
      this.check.className = `check ${file.matches ? "good" : "bad"}`;
    } else {
      this.check.textContent = `fingerprint ${hex(p.fingerprint)}`;
      this.check.className = "check";
    }
    this.check.dataset.unit = this.addr;
    this.check.dataset.signal = "fingerprint";
    this.check.dataset.value = String(p.fingerprint);
    this.cells.forEach((c, n) => {
      const ch = p.values[n] || " ";
      const reached = ch !== " ";
      c.dataset.value = reached ? ch : "";
      c.textContent = reached ? (c.pops ? `→${ch}` : ch) : "";
      c.parentElement.classList.toggle("unreached", !reached);
    });
  }
}

function hex(n) {
  return n.toString(16).toUpperCase().padStart(4, "0");
}
