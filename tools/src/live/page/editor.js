// Edit in the Program tab: the listing in a text area with a line-number gutter, checked as
// you type by the core's own parser (POST /api/check: the messages `utile asm` gives, each on
// its line), Open a .utl file from the PC, Save the listing, Send it to the uTile
// (POST /api/units/{addr}/program: stop, READ, read back, STORE if ticked, EX0). A plain
// textarea: no editor library, so nothing beyond the page's own files is served.

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
    this.gutter = el("div", { class: "gutter", "aria-hidden": "true" });
    this.text = el("textarea", { class: "code", spellcheck: "false", wrap: "off",
      "data-unit": addr, "data-editor": "listing", "aria-label": `listing for uTile ${addr}` });
    this.text.addEventListener("input", () => this.changed());
    this.text.addEventListener("scroll", () => { this.gutter.scrollTop = this.text.scrollTop; });
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
      this.sent,
      el("div", { class: "editor" }, this.gutter, this.text), this.status, this.problems);
    this.root.hidden = true;
  }

  // Shows or hides the editor; the first time, with the program the uTile runs.
  toggle() {
    this.root.hidden = !this.root.hidden;
    if (!this.root.hidden && this.text.value === "") this.fromUtile();
  }

  fromUtile() {
    const lines = this.listing();
    if (!lines.length) return;
    this.set(["FILL", ...lines.filter((l) => l.name !== ".....")
      .map((l) => `${String(l.n).padStart(3, "0")} ${l.name}`)].join("\n") + "\n");
  }

  set(text) {
    this.text.value = text;
    this.changed();
  }

  async open() {
    const f = this.file.files[0];
    if (!f) return;
    this.set(await f.text());
    this.name = f.name;
    this.file.value = "";
  }

  save() {
    const blob = new Blob([this.text.value], { type: "text/plain" });
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
        body: JSON.stringify({ listing: this.text.value, store: this.store.checked, run: true }),
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

  // The gutter follows the text; the check runs once typing pauses.
  changed() {
    this.numbers([]);
    this.status.textContent = "checking…";
    this.status.dataset.value = "";
    clearTimeout(this.timer);
    this.timer = setTimeout(() => this.check(), CHECK_AFTER_MS);
  }

  // Line numbers 1..n, those with a problem marked (with the message as their title).
  numbers(problems) {
    const bad = new Map(problems.map((p) => [p.line, p.message]));
    const n = Math.max(1, this.text.value.split("\n").length);
    this.gutter.replaceChildren(...Array.from({ length: n }, (_, i) => {
      const d = el("div", { text: String(i + 1), "data-gutter-line": i + 1 });
      if (bad.has(i + 1)) {
        d.className = "bad";
        d.title = bad.get(i + 1);
      }
      return d;
    }));
    this.gutter.scrollTop = this.text.scrollTop;
  }

  async check() {
    const asked = ++this.asked;
    let problems;
    try {
      const res = await fetch("/api/check", {
        method: "POST",
        headers: { "content-type": "application/json" },
        body: JSON.stringify({ listing: this.text.value }),
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
    if (asked !== this.asked) return; // a newer check is on its way
    this.numbers(problems);
    this.problems.replaceChildren(...problems.map((p) =>
      el("li", { "data-problem-line": p.line, text: `line ${p.line}: ${p.message}` })));
    this.status.dataset.value = String(problems.length);
    this.status.textContent = problems.length
      ? `${problems.length} problem${problems.length > 1 ? "s" : ""}, as utile asm finds them`
      : "no problems: the listing is a program";
  }
}
