// The terminal on the Nano's serial port: xterm.js shows uTile's VT100 screen (80×24) and
// sends every key and paste to the firmware (UTF-8, as a terminal program does). Its font
// is sized so the 80 columns fit the page's width, down to a phone's.

import { Terminal } from "./vendor/xterm.mjs";

// A monospace character's width over its font size (DejaVu Sans Mono and the like), and the
// font sizes allowed.
const CHAR_WIDTH = 0.62;
const FONT_MIN = 5;
const FONT_MAX = 15;

// The font size that fits 80 columns in `box`'s container.
function fitFont(box) {
  const room = box.parentElement.clientWidth - 24;
  return Math.max(FONT_MIN, Math.min(FONT_MAX, Math.floor(room / (80 * CHAR_WIDTH))));
}

// xterm.js in `box`, on `serial`.
export function openTerminal(box, serial) {
  const term = new Terminal({
    cols: 80,
    rows: 24,
    fontSize: fitFont(box),
    cursorBlink: true,
    convertEol: false,
    theme: { background: "#000000" },
  });
  term.open(box);
  const utf8 = new TextEncoder();
  term.onData((text) => serial.send(utf8.encode(text)));
  term.onBinary((text) => serial.send(Array.from(text, (c) => c.charCodeAt(0) & 0xff)));
  serial.listen((bytes) => term.write(bytes));
  let fitted = term.options.fontSize;
  window.addEventListener("resize", () => {
    const size = fitFont(box);
    if (size !== fitted) {
      fitted = size;
      term.options.fontSize = size;
    }
  });
  // The browser test reads the screen from here.
  window.utileTerminal = term;
  return term;
}
