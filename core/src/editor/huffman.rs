//! The texts' compile-time coder: run-length, then a canonical Huffman code from the
//! symbols' frequencies over all texts. Everything here is `const fn`, evaluated by the
//! compiler; the firmware holds only the result and `text.rs`'s reader.
//!
//! The texts are ASCII: a run of 6 or more equal bytes (spaces, dashes, `=`) becomes the
//! symbol RUN, a 6-bit count and the byte, and each text ends with the symbol END; then every
//! symbol gets a canonical Huffman code from its frequency over all texts (2,294 bytes of
//! coded text take 1,244 with their ENDs, about 4.3 bits each), and the blob is the texts'
//! codes back to back.
//! Codes of one length are consecutive, so the reader needs only the number of codes of
//! each length and the symbols in code order.

/// The symbol that ends a text (no text contains a NUL).
pub(super) const END: u8 = 0;
/// The symbol that starts a run (no text contains it).
pub(super) const RUN: u8 = 1;
/// Bits of a run's count.
pub(super) const RUN_BITS: u8 = 6;
/// Runs shorter than this stay as they are.
const RUN_MIN: usize = 6;
/// The longest code the decoder reads (a compile-time check holds the texts to it).
const MAX_LEN: usize = 15;

/// Length of the run of `s[i]` starting at `i` (at most what `RUN_BITS` can count).
const fn run_at(s: &[u8], i: usize) -> usize {
    let mut n = 1;
    while i + n < s.len() && s[i + n] == s[i] && n < (1 << RUN_BITS) - 1 {
        n += 1;
    }
    n
}

/// How often each symbol occurs over all texts.
const fn frequencies(parts: &[&str]) -> [u16; 128] {
    let mut f = [0u16; 128];
    let mut p = 0;
    while p < parts.len() {
        let s = parts[p].as_bytes();
        f[END as usize] += 1;
        let mut i = 0;
        while i < s.len() {
            assert!(
                s[i] > RUN && s[i] < 128,
                "texts are ASCII without NUL or 0x01"
            );
            let n = run_at(s, i);
            if n >= RUN_MIN {
                f[RUN as usize] += 1;
            }
            f[s[i] as usize] += 1;
            i += if n >= RUN_MIN { n } else { 1 };
        }
        p += 1;
    }
    f
}

/// Huffman code lengths for the frequencies (0 for an unused symbol): join the two lightest
/// trees until one is left; a symbol's length is its depth.
const fn lengths(f: &[u16; 128]) -> [u8; 128] {
    const NONE: usize = usize::MAX;
    let mut weight = [0u32; 256];
    let mut parent = [NONE; 256];
    let mut alive = [false; 256];
    let mut nodes = 128;
    let mut i = 0;
    while i < 128 {
        weight[i] = f[i] as u32;
        alive[i] = f[i] > 0;
        i += 1;
    }
    loop {
        let (mut a, mut b) = (NONE, NONE);
        let mut j = 0;
        while j < nodes {
            if alive[j] {
                if a == NONE || weight[j] < weight[a] {
                    b = a;
                    a = j;
                } else if b == NONE || weight[j] < weight[b] {
                    b = j;
                }
            }
            j += 1;
        }
        if b == NONE {
            break;
        }
        weight[nodes] = weight[a] + weight[b];
        alive[nodes] = true;
        alive[a] = false;
        alive[b] = false;
        parent[a] = nodes;
        parent[b] = nodes;
        nodes += 1;
    }
    let mut len = [0u8; 128];
    let mut s = 0;
    while s < 128 {
        if f[s] > 0 {
            let mut d = 0;
            let mut n = s;
            while parent[n] != NONE {
                n = parent[n];
                d += 1;
            }
            assert!(d >= 1 && d <= MAX_LEN, "code length out of range");
            len[s] = d as u8;
        }
        s += 1;
    }
    len
}

/// The code: each symbol's length and value, and the decoder's tables.
pub(super) struct Code {
    /// Each symbol's code length (0: unused).
    len: [u8; 128],
    /// Each symbol's code.
    value: [u16; 128],
    /// Symbols in code order (by length, then by symbol).
    pub(super) order: [u8; 128],
    /// Symbols in use.
    pub(super) used: usize,
    /// Codes of each length (index 0 unused).
    pub(super) counts: [u8; MAX_LEN + 1],
    /// The longest code.
    pub(super) longest: usize,
}

/// The canonical code for the lengths: codes of one length are consecutive, in symbol order.
const fn canonical(len: [u8; 128]) -> Code {
    let mut c = Code {
        len,
        value: [0; 128],
        order: [0; 128],
        used: 0,
        counts: [0; MAX_LEN + 1],
        longest: 0,
    };
    let mut code = 0u16;
    let mut l = 1;
    while l <= MAX_LEN {
        let mut s = 0;
        while s < 128 {
            if len[s] as usize == l {
                c.value[s] = code;
                code += 1;
                c.order[c.used] = s as u8;
                c.used += 1;
                c.counts[l] += 1;
                c.longest = l;
            }
            s += 1;
        }
        code <<= 1;
        l += 1;
    }
    c
}

/// The canonical Huffman code of `parts`.
pub(super) const fn code(parts: &[&str]) -> Code {
    canonical(lengths(&frequencies(parts)))
}

/// Bits of `s` coded, its END included.
pub(super) const fn coded_len(code: &Code, s: &[u8]) -> usize {
    let (mut i, mut bits) = (0, code.len[END as usize] as usize);
    while i < s.len() {
        let n = run_at(s, i);
        if n >= RUN_MIN {
            bits += code.len[RUN as usize] as usize + RUN_BITS as usize;
        }
        bits += code.len[s[i] as usize] as usize;
        i += if n >= RUN_MIN { n } else { 1 };
    }
    bits
}

/// Bit offset of `parts[n]` (the bits of the parts before it).
pub(super) const fn offset_of(code: &Code, parts: &[&str], n: usize) -> usize {
    let mut i = 0;
    let mut sum = 0;
    while i < n {
        sum += coded_len(code, parts[i].as_bytes());
        i += 1;
    }
    sum
}

/// Write the `len` low bits of `v` at bit `at` of `out`; the bit after them.
const fn put<const N: usize>(out: &mut [u8; N], mut at: usize, v: u16, len: u8) -> usize {
    let mut k = len;
    while k > 0 {
        k -= 1;
        if v >> k & 1 != 0 {
            out[at >> 3] |= 0x80 >> (at & 7);
        }
        at += 1;
    }
    at
}

/// All parts, coded and concatenated.
pub(super) const fn join<const N: usize>(code: &Code, parts: &[&str]) -> [u8; N] {
    let mut out = [0u8; N];
    let mut at = 0;
    let mut p = 0;
    while p < parts.len() {
        let s = parts[p].as_bytes();
        let mut i = 0;
        while i < s.len() {
            let n = run_at(s, i);
            if n >= RUN_MIN {
                let r = RUN as usize;
                at = put(&mut out, at, code.value[r], code.len[r]);
                at = put(&mut out, at, n as u16, RUN_BITS);
            }
            let c = s[i] as usize;
            at = put(&mut out, at, code.value[c], code.len[c]);
            i += if n >= RUN_MIN { n } else { 1 };
        }
        let e = END as usize;
        at = put(&mut out, at, code.value[e], code.len[e]);
        p += 1;
    }
    out
}
