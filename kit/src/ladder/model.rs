//! The ladder model: rungs of series/parallel networks of contacts feeding coils, and
//! instruction blocks for lines that have no ladder form.
//!
//! Every element keeps the listing lines it stands for ([`Contact::lines`], …), so a page can
//! light it from the value each line leaves on top of the bit stack (the value after an
//! element's last line is the power leaving it): the model never evaluates anything itself,
//! the core's engine does.

use std::string::String;
use std::vec::Vec;

use utile_core::engine::{COUNTERS, SET_POINTS, UNITS};
use utile_core::opcodes::{self, CLR, SET};

/// A contact: one bit pushed (`A0.`, `AL0.`, `TQ3.`, `SET`, …), normally open or closed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Contact {
    /// The push opcode (`0x20..=0x7F`, `CLKA.`..`CLKC.`, `SET` or `CLR`).
    pub op: u8,
    /// Normally closed: the push is followed by `!`.
    pub negated: bool,
    /// The listing lines (one, or two with the `!`).
    pub lines: Vec<u8>,
}

/// What a contact reads, in IEC 61131-3's words.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContactKind {
    /// A level (`An.`, `Yn.`, `TQm.`, …).
    Level,
    /// `ALn.`: the rising edge of input n (IEC's `P` contact).
    Rising,
    /// `ATn.`: the falling edge of input n (IEC's `N` contact).
    Falling,
    /// `SET`: always closed (a plain wire).
    Short,
    /// `CLR`: always open.
    Open,
}

impl Contact {
    /// The listing's name of the bit without its dot (`A0`, `AL0`, `TQ3`, `CLKA`, `1`, `0`).
    pub fn signal(&self) -> String {
        match self.op {
            SET => "1".into(),
            CLR => "0".into(),
            op => op_word(op).trim_end_matches('.').into(),
        }
    }

    /// Level, edge, or a constant.
    pub fn kind(&self) -> ContactKind {
        match self.op {
            SET => ContactKind::Short,
            CLR => ContactKind::Open,
            op if (opcodes::PUSH_AL..opcodes::PUSH_AL + 6).contains(&op) => ContactKind::Rising,
            op if (opcodes::PUSH_AT..opcodes::PUSH_AT + 6).contains(&op) => ContactKind::Falling,
            _ => ContactKind::Level,
        }
    }
}

/// A network: the power a part of a rung passes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Net {
    /// One contact.
    Contact(Contact),
    /// Series: the first, then the second (`AND`, on `line`).
    Series(Box<Net>, Box<Net>, u8),
    /// Parallel: either (`OR`, on `line`).
    Parallel(Box<Net>, Box<Net>, u8),
    /// IEC's XOR function on two networks (`XOR`, on `line`).
    Xor(Box<Net>, Box<Net>, u8),
    /// IEC's NOT function on a network that is not a single contact (`!`, on `line`).
    Not(Box<Net>, u8),
}

/// An output: a bit popped (`.Y0`, `.S3`, `.TK0`, …), perhaps negated (`!` before it).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Coil {
    /// The pop opcode (`0x80..=0xE7`).
    pub op: u8,
    /// Negated coil: the pop is preceded by `!`.
    pub negated: bool,
    /// The listing lines (one, or two with the `!`).
    pub lines: Vec<u8>,
}

/// What a coil drives, in IEC 61131-3's words.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CoilKind {
    /// `.Yn`, `.Un`, `.Vn`: a plain coil.
    Plain,
    /// `.Sm`: the set input of flip-flop m (Q changes at END, reset wins).
    Set,
    /// `.Rm`: the reset input of flip-flop m.
    Reset,
    /// `.TKm`: the trigger of timer m, IEC's TOF (`TQm` on at once, off a preset after).
    TimerTrigger,
    /// `.TRm`: the reset of timer m.
    TimerReset,
    /// `.CUm`: the count input of counter m, IEC's CTU.
    CountUp,
    /// `.CRm`: the reset of counter m.
    CounterReset,
}

impl Coil {
    /// The listing's name without its dot (`Y0`, `S3`, `TK0`, `CR1`).
    pub fn signal(&self) -> String {
        op_word(self.op).trim_start_matches('.').into()
    }

    /// Which kind of output.
    pub fn kind(&self) -> CoilKind {
        match self.op {
            op if op < opcodes::POP_S => CoilKind::Plain,
            op if op < opcodes::POP_R => CoilKind::Set,
            op if op < opcodes::POP_TK => CoilKind::Reset,
            op if op < opcodes::POP_TR => CoilKind::TimerTrigger,
            op if op < opcodes::POP_CU => CoilKind::TimerReset,
            op if op < opcodes::POP_CR => CoilKind::CountUp,
            _ => CoilKind::CounterReset,
        }
    }

    /// The unit number of a flip-flop, timer or counter output (the `m` of `.TKm`).
    pub fn unit(&self) -> u8 {
        opcodes::family_of(self.op).map_or(0, |(_, n)| n)
    }
}

/// A logic function applied to the power arriving at a point of a rung.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Step {
    /// In series with a network (`net AND`).
    And(Net, u8),
    /// OR with a network (an IEC OR function: the power in, the network beside it).
    Or(Net, u8),
    /// XOR with a network.
    Xor(Net, u8),
    /// NOT (`!`).
    Not(u8),
    /// A tap (`DUP`, on the line given): the power also drives a flow of its own (drawn
    /// below), and goes on unchanged.
    Tap(Box<Flow>, u8),
    /// The power split (`DUP`, on the first line given), one copy through the steps, then
    /// joined with the other by an IEC function (`AND`, `OR` or `XOR`: the opcode and its
    /// line).
    Merge(Vec<Step>, u8, u8, u8),
}

/// Where the power goes after the rung's network.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Flow {
    /// Into a coil.
    Coil(Coil),
    /// Through a function, then on.
    Then(Step, Box<Flow>),
    /// Split (`DUP`, on `line`): the first branch is drawn on top and runs first.
    Split(Box<Flow>, Box<Flow>, u8),
}

/// One rung: a network from the left rail, then its outputs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rung {
    /// The power from the left rail.
    pub net: Net,
    /// What the power drives.
    pub flow: Flow,
}

/// Lines that have no ladder form (SWAP, byte moves, a stack left non-empty, END, KEY, NOP),
/// never drawn as rungs: shown as their lines.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Block {
    /// (line, opcode) in order.
    pub lines: Vec<(u8, u8)>,
}

/// One item of a ladder program, in scan order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Item {
    /// A rung.
    Rung(Rung),
    /// An instruction block.
    Block(Block),
}

/// A whole program as ladder: its items in scan order, what fills the lines after them, and
/// its presets and set-points.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Ladder {
    /// Rungs and blocks, in scan order from line 0.
    pub items: Vec<Item>,
    /// The opcode of every line after the items (NOP as after FILL, or blank).
    pub fill: u8,
    /// Timer presets T0..TF.
    pub presets: [u8; UNITS],
    /// Counter presets C0..C7.
    pub counter_presets: [u16; COUNTERS],
    /// Analog set-points S6, S7.
    pub set_points: [u16; SET_POINTS],
}

/// The listing's word for an opcode (`A0.`, `.Y0`, `END`), or `$XX` for an unassigned byte.
pub fn op_word(op: u8) -> String {
    match opcodes::name(op) {
        Some(n) => n.as_str().into(),
        None if op == opcodes::BLANK => ".....".into(),
        None => format!("${op:02X}"),
    }
}

/// Whether `op` pushes one bit and nothing else (a contact).
pub fn is_push(op: u8) -> bool {
    matches!(
        op,
        SET | CLR | opcodes::CLKA | opcodes::CLKB | opcodes::CLKC
    ) || (opcodes::PUSH_A..opcodes::POP_Y).contains(&op) && opcodes::is_valid(op)
}

/// Whether `op` pops one bit into an output (a coil).
pub fn is_pop(op: u8) -> bool {
    (opcodes::POP_Y..=opcodes::POP_LAST).contains(&op)
}
