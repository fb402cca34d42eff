// The Nano's serial port, the one owner of the simulated USART's bytes. What the firmware
// sends goes to whoever listens (the terminal; a line machine that speaks Modbus between
// the USART and the terminal would be the one listener and pass the editor's screens on);
// what is sent to the firmware goes onto the line at 19200 baud, back to back behind what is
// still on its way, as a terminal's bytes on a cable.

export class Serial {
  // `nano`: the adapter's Nano.
  constructor(nano) {
    this.nano = nano;
    this.listeners = [];
    // What the firmware sent before anyone listened (the Nano starts before the terminal).
    this.backlog = [];
  }

  // `f(bytes, timed)` with each batch the firmware sent: a Uint8Array, and {byte, cycle}
  // each (the cycle its stop bit ended). The first listener gets what came before it too.
  listen(f) {
    this.listeners.push(f);
    const waiting = this.backlog.splice(0);
    if (waiting.length) f(Uint8Array.from(waiting, (t) => t.byte), waiting);
  }

  // Bytes (a Uint8Array or numbers) onto the line into the Nano.
  send(bytes) {
    this.nano.send(Array.from(bytes));
  }

  // Bytes still on their way into the Nano.
  get pending() {
    return this.nano.pendingInput;
  }

  // Hands what the firmware sent since the last call to the listeners (the clock calls it
  // after every slice).
  pump() {
    const timed = this.nano.takeOutput();
    if (timed.length === 0) return;
    if (this.listeners.length === 0) {
      this.backlog.push(...timed);
      return;
    }
    const bytes = Uint8Array.from(timed, (t) => t.byte);
    for (const f of this.listeners) f(bytes, timed);
  }
}
