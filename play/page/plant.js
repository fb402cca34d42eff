// The tank on the page's Nano: the kit's plant model (the one `cargo nano --plant tank`
// runs), in the WebAssembly module, fed the chip's cycles and outputs after every slice; its
// level goes to A6 and A7. Moving the A6 slider moves the level: the tank goes on from there.

export class Plant {
  // `utile`: the WebAssembly module (utile.js); `nano`: the adapter's Nano.
  constructor(utile, nano) {
    this.utile = utile;
    this.nano = nano;
    this.running = false;
  }

  // Starts plant `name` at A6's level: null, or why not.
  start(name) {
    const why = this.utile.plantStart(name, this.mv(), this.nano.cycles);
    this.running = why === null;
    return why;
  }

  stop() {
    this.utile.plantStop();
    this.running = false;
  }

  // A6 in millivolts.
  mv() {
    return Math.round(this.nano.volts.A6 * 1000);
  }

  // The chip ran on: the level moves, onto A6 and A7.
  step() {
    if (!this.running) return;
    const mv = this.utile.plantStep(this.nano.cycles, this.nano.y, this.mv());
    this.nano.setVolts("A6", mv / 1000);
    this.nano.setVolts("A7", mv / 1000);
  }
}
