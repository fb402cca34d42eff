// The Examples tab: every program of examples/ (examples/index.json, written by
// ./x play --build, with each listing's text) with its title; its listing shown on request,
// its .utl and its .hex to download. The .hex is made here by the kit's listing code in the
// WebAssembly module: the file `utile asm` writes and READ takes. It is made in the click
// itself, the link's address set before the browser follows it: a download the user asked
// for, never one started after an await (which a browser may refuse as unrequested).

import { el } from "./live/dom.js";

async function fetchText(url) {
  const res = await fetch(url);
  if (!res.ok) throw new Error(`${url}: the server answered ${res.status}`);
  return res.text();
}

export class Examples {
  // `root`: the list's element; `notify(text)`: says what went wrong, in words.
  constructor(root, notify) {
    this.root = root;
    this.notify = notify;
    this.utile = null;
    this.hexButtons = [];
  }

  // Lists them (examples/index.json).
  async load() {
    const list = JSON.parse(await fetchText("./examples/index.json"));
    for (const ex of list) this.root.append(this.row(ex));
    this.root.dataset.count = String(list.length);
  }

  // `utile`: the WebAssembly module; the .hex buttons work from now on.
  attach(utile) {
    this.utile = utile;
    for (const b of this.hexButtons) b.removeAttribute("aria-disabled");
  }

  row(ex) {
    const base = ex.name.split("/").pop();
    const pre = el("pre", { class: "listing-text", hidden: "" });
    const show = el("button", { class: "scan-button", type: "button", "data-action": "show",
      text: "Show", title: "show the listing" });
    show.addEventListener("click", () => {
      if (!pre.textContent) pre.textContent = ex.text;
      pre.hidden = !pre.hidden;
      show.textContent = pre.hidden ? "Show" : "Hide";
    });
    const utl = el("a", { class: "scan-button", href: ex.file, download: `${base}.utl`,
      "data-action": "utl", text: ".utl", title: "the listing, as a file" });
    const hex = el("a", { class: "scan-button", href: "#", download: `${base}.hex`,
      "data-action": "hex", "aria-disabled": "true",
      title: "the Intel HEX file READ takes (WRITE's format)", text: ".hex" });
    let url = null;
    hex.addEventListener("click", (event) => {
      if (!this.utile) {
        event.preventDefault();
        return;
      }
      if (url) return;
      const made = this.utile.listingToHex(ex.text);
      if (!made.hex) {
        event.preventDefault();
        this.notify(`${ex.name}: ${made.problems.map((p) => `line ${p.line}: ${p.message}`).join("; ")}`);
        return;
      }
      url = URL.createObjectURL(new Blob([made.hex], { type: "text/plain" }));
      hex.href = url;
    });
    this.hexButtons.push(hex);
    return el("article", { class: "example", "data-example": ex.name },
      el("div", { class: "example-head" },
        el("b", { class: "example-name", text: ex.name }),
        el("span", { class: "example-title", text: ex.title }),
        el("span", { class: "example-actions" }, show, utl, hex)),
      pre);
  }
}
