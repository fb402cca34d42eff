//! The playground's WebAssembly module (`out/play/utile_play.wasm`): the platform-free Rust
//! the page needs, so the page has no second parser, encoder or plant in JavaScript. Built
//! by `./x play --build` for `wasm32-unknown-unknown`; `play/page/utile.js` is its glue.
//!
//! The interface is plain `extern "C"` exports (no wasm-bindgen: nothing to install beside
//! the toolchain, no generated JavaScript). Bytes go through two buffers the module owns:
//! the page asks [`utile_input`] for room, writes its bytes there (UTF-8 text, or a file's
//! bytes) and calls a function; the function's answer is in the reply buffer
//! ([`utile_reply_ptr`], [`utile_reply_len`]) until the next call. Each function returns 0
//! when it did what was asked, else what it says.
//!
//! - [`program`]: a listing checked (`utile asm`'s messages), a listing to the Intel HEX
//!   file READ takes, a hex file back to a listing;
//! - [`plant`]: the kit's plant model (`--plant tank`) on the page's chip.

pub mod plant;
pub mod program;

use std::cell::RefCell;

thread_local! {
    /// The page's bytes for the next call.
    static INPUT: RefCell<Vec<u8>> = const { RefCell::new(Vec::new()) };
    /// The last call's answer.
    static REPLY: RefCell<Vec<u8>> = const { RefCell::new(Vec::new()) };
}

/// Room for `len` bytes of input (zeros): the page writes its bytes at the address returned,
/// before its next call into the module.
#[no_mangle]
pub extern "C" fn utile_input(len: usize) -> *mut u8 {
    INPUT.with_borrow_mut(|input| {
        input.clear();
        input.resize(len, 0);
        input.as_mut_ptr()
    })
}

/// Where the last call's answer starts.
#[no_mangle]
pub extern "C" fn utile_reply_ptr() -> *const u8 {
    REPLY.with_borrow(|reply| reply.as_ptr())
}

/// How many bytes the last call's answer has.
#[no_mangle]
pub extern "C" fn utile_reply_len() -> usize {
    REPLY.with_borrow(|reply| reply.len())
}

/// Runs `f` on the input (taken: the next call starts empty), keeps its answer as the reply
/// and returns its code.
fn answer(f: impl FnOnce(&[u8]) -> (u32, Vec<u8>)) -> u32 {
    let input = INPUT.with_borrow_mut(std::mem::take);
    let (code, reply) = f(&input);
    REPLY.with_borrow_mut(|r| *r = reply);
    code
}

/// The input as text (a page's text is UTF-8; anything else is read as best it can be).
fn text(input: &[u8]) -> String {
    String::from_utf8_lossy(input).into_owned()
}

/// The listing in the input checked: the reply is the problems' JSON,
/// `[{"line": 3, "message": "…"}]` (empty when it is good); returns how many there are.
#[no_mangle]
pub extern "C" fn utile_check() -> u32 {
    answer(|input| {
        let problems = program::check(&text(input));
        (problems.len() as u32, program::problems_json(&problems))
    })
}

/// The listing in the input as the Intel HEX text READ takes (WRITE's format, as `utile asm`
/// writes it): 0 with the hex as the reply, or 1 with the problems' JSON.
#[no_mangle]
pub extern "C" fn utile_listing_to_hex() -> u32 {
    answer(|input| match program::to_hex(&text(input)) {
        Ok(hex) => (0, hex),
        Err(problems) => (1, program::problems_json(&problems)),
    })
}

/// The Intel HEX file in the input (as READ would read it) back to a listing (`utile dis`'s):
/// 0 with the listing as the reply, or 1 with why it is refused, in words.
#[no_mangle]
pub extern "C" fn utile_hex_to_listing() -> u32 {
    answer(|input| match program::from_hex(input) {
        Ok(listing) => (0, listing.into_bytes()),
        Err(why) => (1, why.into_bytes()),
    })
}

/// Starts the plant named by the input (`tank`) at `level_mv`, at the chip's `cycle`:
/// 0, or 1 with why as the reply.
#[no_mangle]
pub extern "C" fn utile_plant_start(level_mv: u32, cycle: f64) -> u32 {
    answer(
        |input| match plant::start(&text(input), level_mv, cycle as u64) {
            Ok(()) => (0, Vec::new()),
            Err(why) => (1, why.into_bytes()),
        },
    )
}

/// The chip has run to `cycle` with the outputs `y` (Y0..Y7 as bits 0..7); `set_mv` is the
/// level on A6 now (the rig may have moved it). Returns the plant's level for A6 and A7, in
/// millivolts (`set_mv` again when no plant runs).
#[no_mangle]
pub extern "C" fn utile_plant_step(cycle: f64, y: u32, set_mv: u32) -> u32 {
    plant::step(cycle as u64, y as u8, set_mv)
}

/// Stops the plant: A6 and A7 are the rig's again.
#[no_mangle]
pub extern "C" fn utile_plant_stop() {
    plant::stop();
}
