// uTile live: the page's entry. It follows the server-sent events of /api/events (one
// `state` event per change, the JSON of /api/state), keeps one card per uTile, the program
// view and the terminal, and says in words what a user must do.

import { Card } from "/card.js";
import { LadderView } from "/ladder.js";
import { ProgramView } from "/program.js";
import { RigPanel } from "/rig.js";
import { PAGE } from "/scan.js";
import { openTerminal } from "/terminal.js";
import { askToken } from "/token.js";

const cards = new Map();
// The signal table (/api/signals) by name.
const table = new Map();
const programs = new Map();
const ladders = new Map();
// The Ladder tab's views by address, for the browser test's redraw measure.
window.utileLadders = ladders;
const rigs = new Map();
let terminalOpen = false;

const $ = (id) => document.getElementById(id);

function showTab(name) {
  for (const b of document.querySelectorAll(".tabs button")) {
    b.setAttribute("aria-selected", String(b.dataset.tab === name));
  }
  for (const s of document.querySelectorAll(".tab-page")) {
    s.hidden = s.id !== name;
  }
  if (name === "ladder") for (const v of ladders.values()) v.refresh();
  if (name === "terminal" && !terminalOpen) {
    terminalOpen = true;
    openTerminal($("xterm"));
  }
}

for (const b of document.querySelectorAll(".tabs button")) {
  b.addEventListener("click", () => showTab(b.dataset.tab));
}

// What the line is doing, in words a user acts on.
function banner(state) {
  const el = $("banner");
  let text = "";
  let bad = false;
  if (!state.open) {
    text = `The serial port is not open: ${state.message}`;
    bad = true;
  } else if (state.mode === "edit" || state.mode === "unknown") {
    // The server's words (the EDIT-mode advice is written once, there).
    text = state.message;
  }
  if (state.read_only) {
    text = (text ? text + " " : "") + "Read-only: writes are refused.";
  }
  el.hidden = text === "";
  el.textContent = text;
  el.classList.toggle("bad", bad);
}

function header(state) {
  $("port").textContent = state.port;
  const mode = $("mode");
  const word = !state.open ? "closed" : state.mode;
  mode.textContent = { run: "running", edit: "EDIT mode", unknown: "starting", closed: "port closed" }[word];
  mode.className = `pill ${word}`;
  mode.dataset.value = word;
  const busy = Math.round(state.line.busy * 100);
  $("busy").textContent = `${busy} %`;
  $("busy-bar").style.width = `${busy}%`;
  $("tcp").textContent = String(state.line.tcp_clients);
  $("stray").textContent = String(state.line.stray_bytes);
  $("notes").textContent = state.notes.join(" · ");
}

function update(state) {
  header(state);
  banner(state);
  for (const u of state.units) {
    let card = cards.get(u.addr);
    if (!card) {
      card = new Card(u.addr, state.read_only, state.timer_unit_ms, table);
      cards.set(u.addr, card);
      $("plant").append(card.root);
      // The rig's panel beside the inputs and outputs it works (shown while a rig answers).
      const rig = new RigPanel(u.addr, state.read_only, card.refusal);
      rigs.set(u.addr, rig);
      card.root.querySelector(".panels").firstElementChild.after(rig.root);
      const view = new ProgramView(u.addr);
      programs.set(u.addr, view);
      $("program").append(view.root);
      const ladder = new LadderView(u.addr);
      ladders.set(u.addr, ladder);
      $("ladder").append(ladder.root);
    }
    card.update(u);
    rigs.get(u.addr).update(state.rig);
    programs.get(u.addr).update(u);
    // Last: its redraw measure holds the style and layout of this refresh.
    ladders.get(u.addr).update(u);
  }
}

async function connect() {
  try {
    const res = await fetch("/api/signals");
    for (const s of await res.json()) table.set(s.name, s);
  } catch (e) {
    // The cards then show no ranges; the events still come.
  }
  // Named, so that the holds this page makes live while it follows the events (scan.js).
  const events = new EventSource(`/api/events?page=${PAGE}`);
  events.addEventListener("state", (e) => update(JSON.parse(e.data)));
  events.onerror = () => {
    // The browser reconnects by itself; meanwhile nothing on the page is current.
    $("mode").textContent = "no server: is utile live still running?";
    $("mode").className = "pill closed";
  };
}

// Beyond loopback utile live wants its token (token.js): the page asks for it when a read
// or a write gets 401.
window.addEventListener("utile-token", () =>
  askToken("A write was refused: it needs the token (reading is open to all here)."));

async function start() {
  const url = new URL(location.href);
  if (url.searchParams.has("token")) {
    url.searchParams.delete("token");
    history.replaceState(null, "", url);
  }
  const res = await fetch("/api/state").catch(() => null);
  if (res && res.status === 401) {
    $("mode").textContent = "this utile live needs its token";
    const body = await res.json().catch(() => ({}));
    const wrong = typeof body.error === "string" && body.error.startsWith("wrong token");
    askToken(wrong ? "The token this page had was refused (utile live was started again?)." : "");
    return;
  }
  connect();
}

start();
