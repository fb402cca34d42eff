// The terminal on the same cable: xterm.js shows uTile's VT100 screen (80×24) as the line's
// owner passes it on, over the WebSocket /api/terminal; keys go back the same way.

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
  let ws = null;
  const connect = () => {
    ws = new WebSocket(`${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/api/terminal`);
    ws.binaryType = "arraybuffer";
    ws.onmessage = (e) => term.write(new Uint8Array(e.data));
    ws.onclose = () => setTimeout(connect, 1000);
  };
  connect();
  term.onData((d) => {
    if (ws && ws.readyState === WebSocket.OPEN) ws.send(d);
  });
  term.focus();
  window.utileTerminal = term;
  return term;
}
