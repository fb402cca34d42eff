// The playground's entry: uTile's real firmware image (m328-nano-utile.hex, as cargo fw
// builds it) on a simulated Arduino Nano (avr8js through uTile's adapter, sim/nano.js), its
// EEPROM kept in this browser, its serial port on a terminal, its pins on the test rig; the
// WebAssembly module (the kit's listing code and plant) for the examples and the tank.
//
// The Nano starts as soon as the image is read; the terminal (xterm.js, the largest module)
// is loaded beside it and shows what the firmware sent from the start.
//
// URL parameters: `speed=max` runs the Nano unpaced (as fast as this browser can; the speed
// figure says how fast that is).

import { MemoryEeprom, Nano, StorageEeprom } from "./sim/nano.js";
import { Examples } from "./examples.js";
import { Machine } from "./machine.js";
import { Plant } from "./plant.js";
import { RigPanel } from "./rig.js";
import { Serial } from "./serial.js";
import { loadUtile } from "./utile.js";

// The key the EEPROM is kept under in localStorage.
const EEPROM_KEY = "utile-play-eeprom";

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(location.search);

// Says `text` on the banner (`bad`: something failed); an empty text hides it.
function say(text, bad = false) {
  const b = $("banner");
  b.hidden = !text;
  b.textContent = text;
  b.classList.toggle("bad", bad);
}

function showTab(name) {
  for (const b of document.querySelectorAll(".tabs button")) {
    b.setAttribute("aria-selected", String(b.dataset.tab === name));
  }
  for (const s of document.querySelectorAll(".tab-page")) s.hidden = s.id !== name;
}

// The browser's storage, or null when it refuses (a private window may).
function browserStorage() {
  try {
    const s = window.localStorage;
    s.setItem("utile-play-probe", "1");
    s.removeItem("utile-play-probe");
    return s;
  } catch {
    return null;
  }
}

async function start() {
  // The start-up's marks (the browser test's figures): the modules loaded, the image read,
  // the Nano running.
  performance.mark("utile-modules");
  for (const b of document.querySelectorAll(".tabs button")) {
    b.addEventListener("click", () => showTab(b.dataset.tab));
  }
  const store = browserStorage();
  if (!store) {
    $("eeprom-where").querySelector("b").textContent = "for this visit only";
    say("This browser keeps no storage for this page: the EEPROM (STORE) lasts until the page is closed.");
  }
  const res = await fetch("./m328-nano-utile.hex");
  if (!res.ok) throw new Error(`the firmware image m328-nano-utile.hex: the server answered ${res.status}`);
  const image = await res.text();
  performance.mark("utile-image");
  const nano = new Nano(image, {
    eeprom: store ? new StorageEeprom(store, EEPROM_KEY) : new MemoryEeprom(),
  });
  const serial = new Serial(nano);
  const machine = new Machine(nano, { unpaced: params.get("speed") === "max" });
  // The rig first: the jumpers it restores are read by the firmware as it starts.
  const rig = new RigPanel($("rig"), nano, store, (text) => say(text));
  const terminal = import("./terminal.js").then(({ openTerminal }) => openTerminal($("xterm"), serial));
  let plant = null;
  machine.onSlice(() => {
    serial.pump();
    plant?.step();
  });
  machine.onFrame(() => rig.show());
  machine.onError((e) => say(`The simulation stopped: ${e.message}. Reload the page to start again.`, true));
  machine.start();
  performance.mark("utile-running");
  // For the browser test's figures.
  window.utilePlay = { nano, machine, serial };

  await terminal;
  const examples = new Examples($("example-list"), (text) => say(text, true));
  const listed = examples.load().catch((e) => say(`The examples cannot be listed: ${e.message}`, true));
  try {
    const utile = await loadUtile();
    plant = new Plant(utile, nano);
    rig.attachPlant(plant);
    await listed;
    examples.attach(utile);
    window.utilePlay.utile = utile;
  } catch (e) {
    say(`The listing tools (utile_play.wasm) did not load: ${e.message}. The Nano runs without them.`, true);
  }
}

start().catch((e) => say(`The playground could not start: ${e.message}`, true));
