// The program, live: the listing the uTile runs (read over Modbus, SPEC §17) with each line's
// value from the latest picture: the bit on top of the stack after the line, or for a line
// that pops (`.Y0` …) the bit it took (shown with an arrow); `?` where the picture cannot
// tell (edges, toggles, clocks). With --program FILE, whether that listing is the one that runs.
// While the scan is held (SPEC §18), Step line walks a cursor through the held scan's lines
// (data-line-cursor="N" on the current line; the values after it wait); past END it steps
// one scan on the uTile and starts again at line 0.

import { el, errorText } from "/dom.js";
import { Editor } from "/editor.js";
import { scanAction } from "/scan.js";

export class ProgramView {
  constructor(addr) {
    this.addr = addr;
    this.fingerprint = null;
    this.cells = [];
    this.check = el("div", { class: "check" });
    this.table = el("table", { class: "listing" });
    this.note = el("div", { class: "hint", text: "waiting for the program…" });
    this.cursor = null;
    this.held = false;
    this.stepLine = el("button", { class: "scan-button step-line", type: "button",
      "data-action": "step-line", "data-unit": addr, text: "Step line",
      title: "while held: the next line of the held scan; past END, one scan on the uTile" });
    this.stepLine.hidden = true;
    this.stepLine.addEventListener("click", () => this.walk());
    this.why = el("span", { class: "refusal" });
    this.lines = [];
    this.editor = new Editor(addr, () => this.lines);
    const edit = el("button", { class: "scan-button", type: "button", "data-action": "edit",
      "data-unit": addr, text: "Edit", title: "the listing in an editor, checked as you type" });
    edit.addEventListener("click", () => this.editor.toggle());
    this.root = el("div", { class: "program", "data-unit": addr },
      el("h2", { text: `uTile ${addr}` }), this.check, el("div", { class: "scan-control" },
        edit, this.stepLine, this.why), this.editor.root, this.note, this.table);
  }

  // Step line: the cursor to the next line the held scan reaches; past END, one scan.
  async walk() {
    const next = this.cursor === null ? 0 : this.cursor + 1;
    const cell = this.cells[next];
    if (cell && cell.dataset.value !== "") {
      this.cursor = next;
      this.showCursor();
      return;
    }
    this.why.textContent = "";
    const why = await scanAction(this.addr, "step", 1);
    if (why) {
      this.why.textContent = `step refused: ${why}`;
      return;
    }
    this.cursor = 0;
    this.showCursor();
  }

  // Marks the cursor's line; the lines after it keep their values hidden until reached.
  showCursor() {
    this.cells.forEach((c, n) => {
      if (!c) return;
      const row = c.parentElement;
      if (n === this.cursor) row.dataset.lineCursor = String(n);
      else delete row.dataset.lineCursor;
      row.classList.toggle("ahead", this.cursor !== null && n > this.cursor);
    });
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
    this.lines = p.lines;
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
    const held = u.state === "held";
    this.stepLine.hidden = !held;
    this.stepLine.disabled = !!u.scan_control && u.scan_control.supported === false;
    if (!held && this.cursor !== null) {
      this.cursor = null;
      this.showCursor();
    }
    this.held = held;
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
