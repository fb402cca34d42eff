//! `cargo nano` as a user sees it: the real firmware image in the virtual Nano inside a
//! real terminal (a detached tmux session, 80×26), keys typed with `tmux send-keys`, the
//! screen read back with `tmux capture-pane`. Checks the manual's screens (§2.5, §3.1),
//! the editing keys (SPEC §8) and the rig's status line below the uTile screen.

mod support;

use std::time::{Duration, Instant};
use support::vnano::*;

const T: Duration = Duration::from_secs(20);
const TITLE: &str = "<<<< Nano - u T I L E - ATmega328 >>>>";

/// A tmux server of our own (private socket) running `vnano --fast`.
/// The virtual Nano in a tmux session named `nano`, 80 × 26 (the screen and the status line).
struct Session {
    t: Tmux,
}

impl Session {
    fn start(args: &str) -> Session {
        let elf = firmware_elf();
        // The trailing sleep keeps the pane (and vnano's last words) after a quit.
        let cmd = format!(
            "'{VNANO}' --fast --elf '{}' {args}; sleep 30",
            elf.display()
        );
        Session {
            t: Tmux::start("vnano-test", 80, 26, &["-s", "nano"], &cmd),
        }
    }

    fn tmux(&self, args: &[&str]) -> String {
        self.t.run(args)
    }

    /// The screen as text, one string per row.
    fn screen(&self) -> Vec<String> {
        self.tmux(&["capture-pane", "-p", "-t", "nano"])
            .lines()
            .map(str::to_string)
            .collect()
    }

    /// The screen with attributes (SGR sequences) kept.
    fn screen_with_attributes(&self) -> String {
        self.tmux(&["capture-pane", "-p", "-e", "-t", "nano"])
    }

    fn keys(&self, keys: &[&str]) {
        let mut args = vec!["send-keys", "-t", "nano"];
        args.extend_from_slice(keys);
        self.tmux(&args);
    }

    /// Types text literally, then Enter.
    fn enter(&self, text: &str) {
        self.tmux(&["send-keys", "-t", "nano", "-l", text]);
        self.keys(&["Enter"]);
    }

    /// Polls the screen until `pred` holds; panics with the screen on timeout.
    fn wait(&self, what: &str, pred: impl Fn(&[String]) -> bool) -> Vec<String> {
        let deadline = Instant::now() + T;
        loop {
            let screen = self.screen();
            if pred(&screen) {
                return screen;
            }
            if Instant::now() > deadline {
                panic!(
                    "timed out waiting for {what}; screen:\n{}",
                    screen.join("\n")
                );
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// Waits until some row contains `text`.
    fn wait_text(&self, text: &str) -> Vec<String> {
        self.wait(text, |s| s.iter().any(|row| row.contains(text)))
    }

    /// Waits until the cursor line (reverse video) is `line`.
    fn wait_cursor(&self, line: u16) {
        let deadline = Instant::now() + T;
        loop {
            let screen = self.screen_with_attributes();
            let found = cursor_lines(&screen);
            if found == [line] {
                return;
            }
            if Instant::now() > deadline {
                panic!("cursor not on line {line} (reverse video on {found:?}); screen:\n{screen}");
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

/// Screen rows (0-based) of the program page: rows 9..16 (SPEC §8, editor layout).
const PAGE_ROWS: std::ops::RangeInclusive<usize> = 8..=15;

/// Program line numbers whose entry is in reverse video (the cursor line), from a
/// `capture-pane -e` dump: on each page row, the `NNN` tag at or before the first
/// reversed character.
fn cursor_lines(dump: &str) -> Vec<u16> {
    let mut found = Vec::new();
    for (row, line) in dump.lines().enumerate() {
        if !PAGE_ROWS.contains(&row) {
            continue;
        }
        let (plain, reversed) = strip_sgr(line);
        let Some(k) = (0..plain.len()).find(|&i| reversed[i] && plain[i] != b' ') else {
            continue;
        };
        let tag = (0..=k.min(plain.len().saturating_sub(4)))
            .rev()
            .find(|&p| is_tag(&plain, p));
        if let Some(p) = tag {
            if let Ok(n) = std::str::from_utf8(&plain[p..p + 3])
                .unwrap_or("")
                .parse::<u16>()
            {
                found.push(n);
            }
        }
    }
    found
}

/// Plain text of a dumped row and, per byte, whether it is in reverse video.
fn strip_sgr(line: &str) -> (Vec<u8>, Vec<bool>) {
    let b = line.as_bytes();
    let (mut plain, mut rev) = (Vec::new(), Vec::new());
    let mut reverse = false;
    let mut i = 0;
    while i < b.len() {
        if b[i] == 0x1B && b.get(i + 1) == Some(&b'[') {
            let start = i + 2;
            let mut j = start;
            while j < b.len() && !(0x40..=0x7E).contains(&b[j]) {
                j += 1;
            }
            if b.get(j) == Some(&b'm') {
                for p in line[start..j].split(';') {
                    match p {
                        "" | "0" | "27" => reverse = false,
                        "7" => reverse = true,
                        _ => {}
                    }
                }
            }
            i = j + 1;
            continue;
        }
        plain.push(b[i]);
        rev.push(reverse);
        i += 1;
    }
    (plain, rev)
}

/// A program line tag `NNN ` starting at `p` (at the row start or after a space).
fn is_tag(plain: &[u8], p: usize) -> bool {
    p + 4 <= plain.len()
        && plain[p..p + 3].iter().all(u8::is_ascii_digit)
        && plain[p + 3] == b' '
        && (p == 0 || plain[p - 1] == b' ')
}

/// The name shown for program line `n` on the page, if the page shows that line.
fn line_name(screen: &[String], n: u16) -> Option<String> {
    let tag = format!("{n:03} ");
    for (row, text) in screen.iter().enumerate() {
        if !PAGE_ROWS.contains(&row) {
            continue;
        }
        let plain = text.as_bytes();
        let mut from = 0;
        while let Some(pos) = text[from..].find(&tag).map(|p| p + from) {
            if is_tag(plain, pos) {
                return text[pos + tag.len()..]
                    .split_whitespace()
                    .next()
                    .map(str::to_string);
            }
            from = pos + 1;
        }
    }
    None
}

#[test]
fn screen_helpers_find_page_lines_and_the_reverse_video_cursor() {
    let mut dump = "\n".repeat(8);
    dump.push_str("       000 NOP      \x1b[7m001 SET\x1b[0m      016 NOP\n");
    assert_eq!(cursor_lines(&dump), vec![1]);
    let mut dump = "\n".repeat(9);
    dump.push_str("       002 NOP      010 \x1b[7m.Y7  \x1b[27m    018 NOP\n");
    assert_eq!(cursor_lines(&dump), vec![10], "only the name reversed");
    assert_eq!(cursor_lines("000 NOP"), Vec::<u16>::new());
    let mut screen = vec!["   7 6 5 4 3 2 1 0   00000 ".to_string(); 8];
    screen.push("       000 NOP      008 .Y7".to_string());
    assert_eq!(line_name(&screen, 0).as_deref(), Some("NOP"));
    assert_eq!(line_name(&screen, 8).as_deref(), Some(".Y7"));
    assert_eq!(line_name(&screen, 9), None);
}

#[test]
fn title_screen_and_status_line_below_it() {
    let t = Session::start("");
    let screen = t.wait_text(TITLE);
    let screen = if screen.iter().any(|r| r.contains("*** User File 0 ***")) {
        screen
    } else {
        t.wait_text("*** User File 0 ***")
    };
    assert!(screen[0].contains(TITLE), "title on row 1: {screen:?}");
    assert_eq!(line_name(&screen, 0).as_deref(), Some("....."));
    assert_eq!(line_name(&screen, 31).as_deref(), Some("....."));
    assert!(screen.iter().any(|r| r.contains("Enter:")));
    // Row 25: the rig, nothing pressed, all LEDs off.
    let screen = t.wait("status line", |s| {
        s.get(24).is_some_and(|r| r.starts_with("SW A0-A5: "))
    });
    assert!(
        screen[24].starts_with("SW A0-A5: ------  D8:open D9:open  LED Y0-Y7: --------"),
        "{:?}",
        screen[24]
    );
    assert!(
        screen[23].contains("*** User File 0 ***"),
        "uTile's status stays on row 24: {screen:?}"
    );

    // Rig keys: Ctrl-] 2 presses A2, Ctrl-] 9 fits the D9 jumper (outputs inverted: all high).
    t.keys(&["C-]", "2"]);
    t.wait("A2 pressed", |s| {
        s.get(24).is_some_and(|r| r.starts_with("SW A0-A5: --2---"))
    });
    t.keys(&["C-]", "9"]);
    t.wait("D9 fitted", |s| {
        s.get(24).is_some_and(|r| r.contains("D9:GND"))
    });
    t.keys(&["C-]", "?"]);
    t.wait("help", |s| {
        s.get(24).is_some_and(|r| r.contains("r reset, q quit"))
    });
    assert!(
        t.screen()[0].contains(TITLE),
        "the uTile screen is untouched by the rig"
    );
    t.keys(&["C-]", "q"]);
    t.wait("quit message", |s| {
        s.iter().any(|r| r.contains("vnano: stopped after"))
    });
}

#[test]
fn fill_set_y7_and_the_editing_keys() {
    let t = Session::start("");
    t.wait_text("*** User File 0 ***");

    // Manual §3.1: fill puts NOP on every line.
    t.enter("fill");
    let screen = t.wait("NOP page", |s| {
        line_name(s, 0).as_deref() == Some("NOP") && line_name(s, 31).as_deref() == Some("NOP")
    });
    assert_eq!(line_name(&screen, 7).as_deref(), Some("NOP"));
    t.wait_cursor(0);

    // SET pushes 1, .Y7 writes it to Y7: the LED lights on the status line.
    t.enter("SET");
    t.wait("SET stored", |s| line_name(s, 0).as_deref() == Some("SET"));
    t.enter(".Y7");
    t.wait(".Y7 stored", |s| line_name(s, 1).as_deref() == Some(".Y7"));
    t.wait("Y7 lit", |s| {
        s.get(24).is_some_and(|r| r.contains("LED Y0-Y7: -------7"))
    });
    t.wait_cursor(2);

    // Backspace erases the typo: ENDX<BS> stores END.
    t.tmux(&["send-keys", "-t", "nano", "-l", "ENDX"]);
    t.keys(&["BSpace", "Enter"]);
    t.wait("END stored", |s| line_name(s, 2).as_deref() == Some("END"));
    t.wait_cursor(3);

    // Up/Down move the cursor line.
    t.keys(&["Up"]);
    t.wait_cursor(2);
    t.keys(&["Up", "Up"]);
    t.wait_cursor(0);
    t.keys(&["Down"]);
    t.wait_cursor(1);

    // Insert at line 1: a NOP goes in, .Y7 and END move down.
    t.keys(&["IC"]);
    t.wait("inserted", |s| {
        line_name(s, 1).as_deref() == Some("NOP")
            && line_name(s, 2).as_deref() == Some(".Y7")
            && line_name(s, 3).as_deref() == Some("END")
    });
    // Delete at line 1: they move back up.
    t.keys(&["DC"]);
    t.wait("deleted", |s| {
        line_name(s, 1).as_deref() == Some(".Y7") && line_name(s, 2).as_deref() == Some("END")
    });

    // Right shows the next page (032..063), Left the first again.
    t.keys(&["Right"]);
    t.wait("page 2", |s| {
        line_name(s, 32).as_deref() == Some("NOP") && line_name(s, 0).is_none()
    });
    t.keys(&["Left"]);
    t.wait("page 1", |s| line_name(s, 0).as_deref() == Some("SET"));

    // A number, then Home: jump to that line's page, cursor on it.
    t.enter("100");
    t.keys(&["Home"]);
    t.wait("page of line 100", |s| {
        line_name(s, 96).is_some() && line_name(s, 127).is_some()
    });
    t.wait_cursor(100);
}
