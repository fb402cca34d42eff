// Edit in the Program tab: the listing in CodeMirror 6 (cm.js: line numbers, uTile's words
// coloured, each problem on its line), checked as you type by the core's own parser
// (POST /api/check: the messages `utile asm` gives, also listed below in words), Open a .utl
// file from the PC, Save the listing, Send it to the uTile (POST /api/units/{addr}/program:
// stop, READ, read back, STORE if ticked, EX0). CodeMirror is loaded the first time Edit
// opens; if it cannot be, the editor says why and the rest of the page goes on.

import { el, errorText } from "/dom.js";

// How long typing pauses before the listing is checked.
const CHECK_AFTER_MS = 250;

export class Editor {
  // `addr`: the uTile whose program view holds this editor; `listing()`: the running
  // program's lines ([{n, name}]) to start from.
  constructor(addr, listing) {
    this.addr = addr;
    this.listing = listing;
    this.timer = null;
    this.asked = 0;
    this.cm = null; // cm.js, once loaded
    this.view = null; // its editor, once loaded
    this.loading = null;
    this.box = el("div", { class: "editor", "data-unit": addr });
    this.status = el("div", { class: "check-status", "data-unit": addr });
    this.problems = el("ul", { class: "problems" });
    this.store = el("input", { type: "checkbox", "data-unit": addr, "data-option": "store",
      title: "STORE it into EEPROM too: it autostarts with D8" });
    this.sent = el("div", { class: "send-status", "data-unit": addr, role: "status" });
    this.file = el("input", { type: "file", accept: ".utl,.txt,text/plain" });
    this.file.hidden = true;
    this.file.addEventListener("change", () => this.open());
    const button = (action, label, title, f) => {
      const b = el("button", { class: "scan-button", type: "button", "data-action": action,
        "data-unit": addr, text: label, title });
      b.addEventListener("click", f);
      return b;
    };
    this.root = el("div", { class: "editor-box" },
      el("div", { class: "scan-control" },
        button("open", "Open…", "a .utl listing from this PC", () => this.file.click()),
        button("save", "Save", "the listing as a .utl file", () => this.save()),
        button("reload", "From uTile", "the program the uTile runs, as a listing", () => this.fromUtile()),
        button("send", "Send", "load the listing into the uTile and start it", () => this.send()),
        el("label", { class: "store" }, this.store, " STORE"),
        this.file),
      this.sent, this.box, this.status, this.problems);
    this.root.hidden = true;
  }

  // Shows or hides the editor; the first time, CodeMirror is loaded (shown, so that it can
  // measure itself) with the program the uTile runs.
  async toggle() {
    this.root.hidden = !this.root.hidden;
    if (this.root.hidden || !(await this.start())) return;
    if (this.value() === "") this.fromUtile();
    // The cursor in the text at once, but not on a phone, whose keyboard would cover it.
    if (window.matchMedia("(pointer: fine)").matches) this.view.focus();
  }

  // Loads cm.js and makes the editor, once; false (with the reason shown) when it cannot.
  start() {
    this.loading ??= import("/cm.js").then((cm) => {
      this.cm = cm;
      this.view = cm.listingEditor(this.box, () => this.changed(), {
        "data-unit": String(this.addr), "data-editor": "listing",
        "aria-label": `listing for uTile ${this.addr}` });
      return true;
    }, (e) => {
      this.box.dataset.editor = "missing";
      this.status.textContent = "the editor cannot start: its library (CodeMirror) did not load " +
        `(${e.message || e}); run ./x setup, then build utile again`;
      return false;
    });
    return this.loading;
  }

  // The listing's text ("" before the editor has started).
  value() {
    return this.view ? this.cm.text(this.view) : "";
  }

  fromUtile() {
    const lines = this.listing();
    if (!lines.length) return;
    this.set(["FILL", ...lines.filter((l) => l.name !== ".....")
      .map((l) => `${String(l.n).padStart(3, "0")} ${l.name}`)].join("\n") + "\n");
  }

  // The whole text replaced (checked like typing).
  set(text) {
    if (this.view) this.cm.setText(this.view, text);
  }

  async open() {
    const f = this.file.files[0];
    if (!f) return;
    this.set(await f.text());
    this.name = f.name;
    this.file.value = "";
  }

  save() {
    const blob = new Blob([this.value()], { type: "text/plain" });
    const a = el("a", { href: URL.createObjectURL(blob), download: this.name || `utile-${this.addr}.utl` });
    a.click();
    URL.revokeObjectURL(a.href);
  }

  // Send: after a confirmation, the listing goes to the uTile and starts; the answer says
  // the new program's fingerprint and how long it took, or what went wrong.
  async send() {
    const ok = window.confirm(`Send this listing to uTile ${this.addr}? Its program stops and ` +
      "its outputs go off while the new one is loaded; then the new program starts.");
    if (!ok) return;
    this.sent.dataset.send = "busy";
    this.sent.textContent = "sending: stop, READ, read back" +
      (this.store.checked ? ", STORE" : "") + ", EX0…";
    let res;
    try {
      res = await fetch(`/api/units/${this.addr}/program`, {
        method: "POST",
        headers: { "content-type": "application/json" },
        body: JSON.stringify({ listing: this.value(), store: this.store.checked, run: true }),
      });
    } catch (e) {
      this.sent.dataset.send = "error";
      this.sent.textContent = `not sent: the server did not answer (${e})`;
      return;
    }
    if (!res.ok) {
      this.sent.dataset.send = "error";
      this.sent.textContent = `not sent: ${await errorText(res)}`;
      return;
    }
    const done = await res.json();
    const fp = done.fingerprint.toString(16).toUpperCase().padStart(4, "0");
    this.sent.dataset.send = "ok";
    this.sent.dataset.fingerprint = fp;
    this.sent.textContent = `running: program ${fp}${done.stored ? ", stored" : ""} ` +
      `(${Math.round(done.ms)} ms)`;
  }

  // The check runs once typing pauses; the problems shown stay on their lines until then.
  changed() {
    this.status.textContent = "checking…";
    this.status.dataset.value = "";
    clearTimeout(this.timer);
    this.timer = setTimeout(() => this.check(), CHECK_AFTER_MS);
  }

  async check() {
    const asked = ++this.asked;
    const doc = this.view.state.doc;
    let problems;
    try {
      const res = await fetch("/api/check", {
        method: "POST",
        headers: { "content-type": "application/json" },
        body: JSON.stringify({ listing: doc.toString() }),
      });
      if (!res.ok) {
        this.status.textContent = `cannot check: ${await errorText(res)}`;
        return;
      }
      problems = await res.json();
    } catch (e) {
      this.status.textContent = `cannot check: the server did not answer (${e})`;
      return;
    }
    // A newer check is on its way when the text changed meanwhile.
    if (asked !== this.asked || !this.cm.showProblems(this.view, doc, problems)) return;
    this.problems.replaceChildren(...problems.map((p) =>
      el("li", { "data-problem-line": p.line, text: `line ${p.line}: ${p.message}` })));
    this.status.dataset.value = String(problems.length);
    this.status.textContent = problems.length
      ? `${problems.length} problem${problems.length > 1 ? "s" : ""}, as utile asm finds them`
      : "no problems: the listing is a program";
  }
}
