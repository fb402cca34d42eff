//! Where things sit on the 80×24 screen (1-based rows and columns; the table in the
//! editor's module docs).

pub(super) const ROW_VALUES: u8 = 6;
pub(super) const COL_BS: u8 = 9;
pub(super) const COL_DATA: u8 = 39;
pub(super) const COL_PORT: u8 = 58;
pub(super) const ROW_PAGE: u8 = 9;
pub(super) const COL_PAGE: u8 = 8;
pub(super) const COL_STEP: u8 = 19;
pub(super) const ROW_INFO: u8 = 19;
pub(super) const ROW_PROMPT: u8 = 22;
pub(super) const COL_PROMPT: u8 = 6;
pub(super) const COL_INPUT: u8 = 13;
pub(super) const ROW_STATUS: u8 = 24;
pub(super) const COL_STATUS_A: u8 = 2;
pub(super) const COL_STATUS_B: u8 = 22;
pub(super) const COL_LDT_MSG: u8 = 47;
pub(super) const COL_STRIKE: u8 = 58;
pub(super) const COL_TITLE: u8 = 21;
/// First and last rows of the work area that help, LDT, READ and WRITE take over.
pub(super) const ROW_AREA: u8 = 8;
pub(super) const AREA_ROWS: u8 = 14;

/// The page (0..7) holding a line.
pub(super) fn page_of(line: u8) -> u8 {
    line >> 5
}

/// Screen position of a line's entry.
pub(super) fn entry_pos(line: u8) -> (u8, u8) {
    let k = line & 31;
    (ROW_PAGE + (k & 7), COL_PAGE + COL_STEP * (k >> 3))
}
