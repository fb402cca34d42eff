//! `cargo nano --load prog.utl`: the program goes into the firmware the way a user would put
//! it there, through READ over the UART, right after boot. The virtual Nano holds the user's
//! keys and the firmware's screen back while this happens (about 2 s of simulated time) and
//! shows the screen from the editor's redraw after READ on: the program on the page.

use utile_core::engine::Program;

use utile_kit::listing;

use super::error::VnanoError;

/// The editor's page is drawn (boot, and back from READ).
const PAGE: &[u8] = b"*** User File 0 ***";
/// READ has started and waits for the file.
const READ_PROMPT: &[u8] = b"Reading file";
/// READ took the file.
const READ_DONE: &[u8] = b"File read completed";
/// READ refused the file.
const READ_ERROR: &[u8] = b"Read error!";
/// The editor's clear-screen sequence: the redraw after READ starts with it.
const CLEAR: &[u8] = b"\x1b[H\x1b[J";

/// Where the loader is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    /// Waiting for the editor's first page.
    Boot,
    /// `READ` typed, waiting for its prompt.
    Prompt,
    /// The hex file is on its way, waiting for READ's verdict.
    Sending,
    /// CR typed after READ: waiting for the page to be redrawn with the program on it.
    Redraw,
    /// Handed over: the redraw and everything after it are the user's.
    Done,
}

/// Feeds one program to the firmware through READ.
#[derive(Clone, Debug)]
pub struct Loader {
    hex: Vec<u8>,
    phase: Phase,
    /// Firmware output of the current phase (searched for the next marker).
    seen: Vec<u8>,
}

/// What the virtual Nano should do after feeding the loader some firmware output.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Step {
    /// Keep running; send these bytes to the firmware (may be empty).
    Send(Vec<u8>),
    /// Loaded: show these bytes (the output from the page redraw's clear-screen on); from
    /// now on the output is the user's.
    Show(Vec<u8>),
    /// The firmware refused the file (should not happen: the image comes from our encoder).
    Failed(String),
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

fn contains(hay: &[u8], needle: &[u8]) -> bool {
    find(hay, needle).is_some()
}

impl Loader {
    /// A loader for `prog` (the hex text is exactly what `utile asm` writes).
    pub fn new(prog: &Program) -> Loader {
        Loader {
            hex: listing::to_hex(prog),
            phase: Phase::Boot,
            seen: Vec::new(),
        }
    }

    /// Parses the listing file `path` and makes a loader for it; errors are `file:line: …`.
    pub fn from_file(path: &std::path::Path) -> Result<Loader, VnanoError> {
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(VnanoError::file("--load", path))?;
        let prog = listing::parse(&name, &text)?;
        Ok(Loader::new(&prog))
    }

    /// Whether the program has been handed over.
    pub fn finished(&self) -> bool {
        self.phase == Phase::Done
    }

    /// Takes the firmware's output since the last call and says what to send next.
    pub fn feed(&mut self, out: &[u8]) -> Step {
        self.seen.extend_from_slice(out);
        let next = match self.phase {
            Phase::Boot if contains(&self.seen, PAGE) => Some((Phase::Prompt, b"READ\r".to_vec())),
            Phase::Prompt if contains(&self.seen, READ_PROMPT) => {
                Some((Phase::Sending, self.hex.clone()))
            }
            Phase::Sending if contains(&self.seen, READ_ERROR) => {
                return Step::Failed(format!(
                    "the firmware refused the program: {}",
                    String::from_utf8_lossy(&self.seen).trim()
                ));
            }
            Phase::Sending if contains(&self.seen, READ_DONE) => {
                Some((Phase::Redraw, b"\r".to_vec()))
            }
            Phase::Redraw => {
                if let Some(at) = find(&self.seen, CLEAR) {
                    self.phase = Phase::Done;
                    let shown = self.seen.split_off(at);
                    self.seen.clear();
                    return Step::Show(shown);
                }
                None
            }
            _ => None,
        };
        match next {
            Some((phase, bytes)) => {
                self.phase = phase;
                self.seen.clear();
                Step::Send(bytes)
            }
            None => Step::Send(Vec::new()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn types_read_sends_the_file_then_ends_read() {
        let prog = listing::parse("t", "A0.\n.Y0\nEND\nT3 = 7\n").unwrap();
        let mut l = Loader::new(&prog);
        assert_eq!(l.feed(b"\x1b[2Jtitle"), Step::Send(vec![]));
        assert_eq!(
            l.feed(b" *** User File 0 *** "),
            Step::Send(b"READ\r".to_vec())
        );
        assert_eq!(l.feed(b"Reading"), Step::Send(vec![]));
        match l.feed(b" file ...") {
            Step::Send(hex) => {
                assert_eq!(hex, listing::to_hex(&prog));
                assert_eq!(listing::from_hex(&hex).unwrap(), prog);
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(l.feed(b"File read completed"), Step::Send(b"\r".to_vec()));
        assert!(!l.finished());
        // The rest of READ's screen is not shown; the redraw is, from its clear-screen on.
        assert_eq!(l.feed(b" - press Enter"), Step::Send(vec![]));
        assert_eq!(
            l.feed(b"menu\x1b[H\x1b[J*** page"),
            Step::Show(b"\x1b[H\x1b[J*** page".to_vec())
        );
        assert!(l.finished());
    }

    #[test]
    fn a_refused_file_is_an_error() {
        let mut l = Loader::new(&Program::blank());
        l.feed(b"*** User File 0 ***");
        l.feed(b"Reading file");
        assert!(
            matches!(l.feed(b"Read error! - checksum"), Step::Failed(m) if m.contains("checksum"))
        );
    }

    #[test]
    fn listing_errors_name_the_file_and_line() {
        let dir = std::env::temp_dir().join(format!("vnano-load-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("bad.utl");
        std::fs::write(&f, "A0.\nFROB\n").unwrap();
        let e = Loader::from_file(&f).unwrap_err().to_string();
        assert!(e.contains("bad.utl:2:") && e.contains("FROB"), "{e}");
        let e = Loader::from_file(&dir.join("none.utl"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("--load") && e.contains("none.utl"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
