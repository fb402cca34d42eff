// The terminal on the same cable: xterm.js shows uTile's VT100 screen (80×24) as the line's
// owner passes it on, over the WebSocket /api/terminal; keys go back the same way. Keys the
// server could not type (the port closed, the line busy) come back as a text message that
// says why: shown under the terminal, never typed later.

import { Terminal } from "/vendor/xterm.mjs";

export function openTerminal(box) {
  const term = new Terminal({
    cols: 80,
    rows: 24,
    fontSize: 14,
    cursorBlink: true,
    convertEol: false,
    theme: { background: "#000000" },
  });
  term.open(box);
  const refused = document.getElementById("terminal-refused");
  let ws = null;
  const connect = () => {
    ws = new WebSocket(`${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/api/terminal`);
    ws.binaryType = "arraybuffer";
    ws.onmessage = (e) => {
      if (typeof e.data === "string") {
        refused.textContent = e.data;
        refused.dataset.refused = e.data;
      } else {
        term.write(new Uint8Array(e.data));
      }
    };
    ws.onclose = () => setTimeout(connect, 1000);
  };
  connect();
  term.onData((d) => {
    if (refused) {
      refused.textContent = "";
      refused.dataset.refused = "";
    }
    if (ws && ws.readyState === WebSocket.OPEN) ws.send(d);
  });
  term.focus();
  window.utileTerminal = term;
  return term;
}
