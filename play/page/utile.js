// The playground's WebAssembly module (utile_play.wasm, built from play/wasm/ by
// ./x play --build): the kit's listing code and plant model, the same Rust as the tools. Its
// interface is plain exports: the page writes its bytes into the module's input buffer
// (utile_input), calls a function, and reads the answer from the reply buffer.

const utf8 = new TextEncoder();
const text = new TextDecoder();

export class Utile {
  // `exports`: the instantiated module's exports.
  constructor(exports) {
    this.x = exports;
  }

  // Calls export `name` with `bytes` as its input: {code, reply (bytes)}.
  call(name, bytes, ...args) {
    const at = this.x.utile_input(bytes.length);
    new Uint8Array(this.x.memory.buffer, at, bytes.length).set(bytes);
    const code = this.x[name](...args);
    const reply = new Uint8Array(this.x.memory.buffer, this.x.utile_reply_ptr(),
      this.x.utile_reply_len()).slice();
    return { code, reply };
  }

  // A listing's problems, as `utile asm` words them: [{line, message}], empty when good.
  check(listing) {
    return JSON.parse(text.decode(this.call("utile_check", utf8.encode(listing)).reply));
  }

  // A listing as the Intel HEX text READ takes: {hex} or {problems}.
  listingToHex(listing) {
    const { code, reply } = this.call("utile_listing_to_hex", utf8.encode(listing));
    return code === 0 ? { hex: text.decode(reply) } : { problems: JSON.parse(text.decode(reply)) };
  }

  // An Intel HEX file (text or bytes) back to its listing: {listing} or {why}.
  hexToListing(hex) {
    const bytes = typeof hex === "string" ? utf8.encode(hex) : hex;
    const { code, reply } = this.call("utile_hex_to_listing", bytes);
    return code === 0 ? { listing: text.decode(reply) } : { why: text.decode(reply) };
  }

  // Starts the plant `name` at `mv` on the chip's `cycle`: null, or why not.
  plantStart(name, mv, cycle) {
    const { code, reply } = this.call("utile_plant_start", utf8.encode(name), mv, cycle);
    return code === 0 ? null : text.decode(reply);
  }

  // The plant's level (mV) after the chip ran to `cycle` with outputs `y`, `mv` on A6.
  plantStep(cycle, y, mv) {
    return this.x.utile_plant_step(cycle, y, mv);
  }

  plantStop() {
    this.x.utile_plant_stop();
  }
}

// Loads the module at `url` (a fetch of the site's own file).
export async function loadUtile(url = "./utile_play.wasm") {
  const res = await fetch(url);
  if (!res.ok) throw new Error(`${url}: the server answered ${res.status}`);
  const { instance } = await WebAssembly.instantiate(await res.arrayBuffer(), {});
  return new Utile(instance.exports);
}
