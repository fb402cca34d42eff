// The EEPROM's contents, kept where the embedder chooses: avr8js asks a backend to read,
// erase and write each byte (its `EEPROMMemoryBackend` interface). Two backends here, both
// plain JavaScript (browser and Node alike): one in memory, one in a Web Storage-like store
// (the page's localStorage; a Map in Node's tests) that saves every change.

/** EEPROM size of the ATmega328P. */
export const EEPROM_BYTES = 1024;

/** The EEPROM in memory: erased (0xFF) at first, or a copy of `bytes`. */
export class MemoryEeprom {
  /** @param {Uint8Array | number[]} [bytes] contents to start with (what does not fit is dropped) */
  constructor(bytes) {
    this.memory = new Uint8Array(EEPROM_BYTES).fill(0xff);
    if (bytes) this.memory.set(Array.from(bytes).slice(0, EEPROM_BYTES));
  }

  /** @param {number} addr */
  readMemory(addr) {
    return this.memory[addr % EEPROM_BYTES];
  }

  /** A write programs zeros only, as the chip's write after its erase does. */
  writeMemory(addr, value) {
    this.memory[addr % EEPROM_BYTES] &= value;
    this.changed();
  }

  /** @param {number} addr */
  eraseMemory(addr) {
    this.memory[addr % EEPROM_BYTES] = 0xff;
    this.changed();
  }

  /** Every byte back to 0xFF: a blank chip. */
  erase() {
    this.memory.fill(0xff);
    this.changed();
    this.flush();
  }

  /** A copy of the contents. */
  bytes() {
    return this.memory.slice();
  }

  /** Called after each change (a subclass marks itself unsaved there). */
  changed() {}

  /** Saves what changed since the last call (the Nano calls it at the end of every run). */
  flush() {}
}

/**
 * The EEPROM kept in a Web Storage-like store under one key, as 2048 hex digits: anything
 * with `getItem(key)` and `setItem(key, text)` (the page's `localStorage`). Read once at
 * start; saved by `flush`, which the Nano calls at the end of every run, so a STORE's few
 * hundred byte writes are one save per batch, not one each.
 */
export class StorageEeprom extends MemoryEeprom {
  /**
   * @param {{getItem(key: string): string | null, setItem(key: string, value: string): void}} store
   * @param {string} [key] the key it is kept under
   */
  constructor(store, key = 'utile-eeprom') {
    super();
    this.store = store;
    this.key = key;
    const saved = store.getItem(key);
    if (typeof saved === 'string' && /^[0-9a-f]{2048}$/i.test(saved)) {
      for (let i = 0; i < EEPROM_BYTES; i++) {
        this.memory[i] = parseInt(saved.substr(2 * i, 2), 16);
      }
    }
  }

  changed() {
    this.dirty = true;
  }

  flush() {
    if (!this.dirty) return;
    this.dirty = false;
    let text = '';
    for (const b of this.memory) text += b.toString(16).padStart(2, '0');
    this.store.setItem(this.key, text);
  }
}
