// The firmware image as avrdude would write it: an Intel HEX file read into the
// ATmega328P's flash (32 KiB, erased to 0xFF), each record's checksum checked.

/** Flash size of the ATmega328P in bytes. */
export const FLASH_BYTES = 32 * 1024;

/** Why a HEX file cannot be loaded: the line (from 1) and what is wrong with it. */
export class HexError extends Error {
  /**
   * @param {number} line the line of the file, from 1
   * @param {string} why what is wrong, in words
   */
  constructor(line, why) {
    super(`firmware image, line ${line}: ${why}`);
    this.name = 'HexError';
    this.line = line;
  }
}

/**
 * Reads an Intel HEX text (data, end-of-file and extended-address records) into flash.
 *
 * @param {string} text the file's text
 * @returns {Uint16Array} the flash as avr8js takes it: 16 Ki little-endian words
 */
export function readHex(text) {
  const bytes = new Uint8Array(FLASH_BYTES).fill(0xff);
  let base = 0;
  let ended = false;
  const lines = text.split(/\r?\n/);
  for (let i = 0; i < lines.length && !ended; i++) {
    const line = lines[i].trim();
    if (line === '') continue;
    const n = i + 1;
    if (line[0] !== ':' || line.length % 2 !== 1 || !/^:[0-9A-Fa-f]+$/.test(line)) {
      throw new HexError(n, 'not a record (":" and hex digits)');
    }
    const rec = new Uint8Array((line.length - 1) / 2);
    for (let k = 0; k < rec.length; k++) {
      rec[k] = parseInt(line.substr(1 + 2 * k, 2), 16);
    }
    if (rec.length < 5 || rec.length !== rec[0] + 5) {
      throw new HexError(n, 'its length byte does not match the record');
    }
    if (rec.reduce((sum, b) => (sum + b) & 0xff, 0) !== 0) {
      throw new HexError(n, 'bad checksum');
    }
    const count = rec[0];
    const offset = (rec[1] << 8) | rec[2];
    const data = rec.subarray(4, 4 + count);
    switch (rec[3]) {
      case 0x00: {
        const at = base + offset;
        if (at + count > FLASH_BYTES) {
          throw new HexError(n, `data at 0x${at.toString(16)} runs past the end of flash`);
        }
        bytes.set(data, at);
        break;
      }
      case 0x01:
        ended = true;
        break;
      case 0x02:
        base = ((data[0] << 8) | data[1]) << 4;
        break;
      case 0x04:
        base = ((data[0] << 8) | data[1]) << 16;
        break;
      case 0x03:
      case 0x05:
        // Start addresses: the AVR always starts at its reset vector.
        break;
      default:
        throw new HexError(n, `unknown record type ${rec[3]}`);
    }
  }
  if (!ended) {
    throw new HexError(lines.length, 'no end-of-file record (is the file cut short?)');
  }
  return new Uint16Array(bytes.buffer);
}
