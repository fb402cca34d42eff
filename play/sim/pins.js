// The Nano's pins as uTile uses them: the rig's inputs (push-buttons A0..A5, jumpers D8 and
// D9) with the chip's pull-ups, which avr8js does not model, and the outputs Y0..Y7 and D10
// with every change and its cycle.

/** Port register addresses of the ATmega328P (data space): PIN, DDR, PORT. */
export const PORTS = {
  B: { PIN: 0x23, DDR: 0x24, PORT: 0x25 },
  C: { PIN: 0x26, DDR: 0x27, PORT: 0x28 },
  D: { PIN: 0x29, DDR: 0x2a, PORT: 0x2b },
};

/** The rig's inputs: a push-button or jumper from the pin to ground. */
export const INPUTS = {
  A0: ['C', 0],
  A1: ['C', 1],
  A2: ['C', 2],
  A3: ['C', 3],
  A4: ['C', 4],
  A5: ['C', 5],
  D8: ['B', 0],
  D9: ['B', 1],
};

/** The outputs: Y0..Y5 = PD2..PD7, Y6 = PB4, Y7 = PB5 (LED L), D10 = PB2 (RS-485 driver enable). */
export const OUTPUTS = {
  Y0: ['D', 2],
  Y1: ['D', 3],
  Y2: ['D', 4],
  Y3: ['D', 5],
  Y4: ['D', 6],
  Y5: ['D', 7],
  Y6: ['B', 4],
  Y7: ['B', 5],
  D10: ['B', 2],
};

/** The output pins' names in a fixed order (the change log's). */
export const OUTPUT_NAMES = Object.keys(OUTPUTS);

/** Which pin name is `input` (case-insensitive), or an error in words. */
export function inputPin(name) {
  const pin = INPUTS[String(name).toUpperCase()];
  if (!pin) throw new Error(`no rig input ${name}: A0..A5, D8 or D9`);
  return pin;
}

/**
 * The rig side of the input pins. A pin held low by the rig reads 0; an input the rig leaves
 * open reads 1 when its pull-up is on (PORTx bit set, DDRx bit clear), as on the chip, and 0
 * when nothing pulls it (avr8js's own reading of every undriven pin). `pullUps` false keeps
 * avr8js's reading for open pins too: the test that shows why the pull-ups are needed.
 */
export class Rig {
  /** @param {boolean} pullUps model the pull-ups */
  constructor(pullUps) {
    this.pullUps = pullUps;
    /** Bits held low by the rig, per port. */
    this.low = { B: 0, C: 0, D: 0 };
  }

  /** Holds a pin low (`true`: pressed, jumper fitted) or lets it go (open). */
  hold(name, low) {
    const [port, bit] = inputPin(name);
    this.low[port] = low ? this.low[port] | (1 << bit) : this.low[port] & ~(1 << bit);
  }

  /** Whether the rig holds the pin low. */
  held(name) {
    const [port, bit] = inputPin(name);
    return (this.low[port] & (1 << bit)) !== 0;
  }

  /** The levels the outside puts on a port's pins: pull-ups where on, the rig's grounds. */
  levels(cpu, port) {
    const r = PORTS[port];
    const pulled = this.pullUps ? cpu.data[r.PORT] & ~cpu.data[r.DDR] & 0xff : 0;
    return pulled & ~this.low[port];
  }

  /**
   * Keeps an avr8js port's input levels true: at once, and after every write to its PORT or
   * DDR register (a port listener runs inside the write, before avr8js updates PINx).
   */
  attach(cpu, gpio, port) {
    gpio.pinValue = this.levels(cpu, port);
    gpio.updatePinRegister(cpu.data[PORTS[port].DDR]);
    gpio.addListener(() => {
      gpio.pinValue = this.levels(cpu, port);
    });
  }
}

/**
 * The outputs' levels as a meter would read them (1 = driven high), and each change with the
 * cycle of the write that made it, for the pins of {@link OUTPUTS}.
 */
export class Outputs {
  constructor() {
    /** @type {{pin: string, level: number, cycle: number}[]} */
    this.changes = [];
    /** Present level of each pin, by name. */
    this.level = Object.fromEntries(OUTPUT_NAMES.map((n) => [n, 0]));
  }

  /** Watches a port of a (new) chip: levels are read from its PORT and DDR. */
  attach(cpu, gpio, port) {
    const mine = OUTPUT_NAMES.filter((n) => OUTPUTS[n][0] === port);
    const r = PORTS[port];
    const look = () => {
      const high = cpu.data[r.PORT] & cpu.data[r.DDR];
      for (const name of mine) {
        const level = (high >> OUTPUTS[name][1]) & 1;
        if (level !== this.level[name]) {
          this.level[name] = level;
          this.changes.push({ pin: name, level, cycle: cpu.cycles });
        }
      }
    };
    look();
    gpio.addListener(look);
  }

  /** Takes the changes since the last call, oldest first. */
  take() {
    return this.changes.splice(0);
  }
}
