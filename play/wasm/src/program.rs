//! Programs for the page, by the kit's listing code (the one `utile asm`, `utile dis` and
//! `utile live`'s `/api/check` use): a listing checked, a listing to the Intel HEX file READ
//! takes, a hex file back to a listing.

use serde::Serialize;
use utile_kit::listing::{self, Problem};

/// One problem as the page gets it.
#[derive(Serialize)]
struct ProblemJson<'a> {
    /// The listing's line, 1-based.
    line: usize,
    /// What is wrong, in `utile asm`'s words.
    message: &'a str,
}

/// The problems of a listing (none when it is good): the kit's [`listing::check`].
pub fn check(text: &str) -> Vec<Problem> {
    listing::check(text)
}

/// `[{"line": …, "message": "…"}, …]`.
pub fn problems_json(problems: &[Problem]) -> Vec<u8> {
    let list: Vec<_> = problems
        .iter()
        .map(|p| ProblemJson {
            line: p.line,
            message: &p.message,
        })
        .collect();
    serde_json::to_vec(&list).unwrap_or_else(|_| b"[]".to_vec())
}

/// A listing as the Intel HEX text READ takes, or its problems.
pub fn to_hex(text: &str) -> Result<Vec<u8>, Vec<Problem>> {
    let problems = check(text);
    if !problems.is_empty() {
        return Err(problems);
    }
    listing::parse("listing", text)
        .map(|prog| listing::to_hex(&prog))
        .map_err(|e| e.problems)
}

/// An Intel HEX file back to the listing of its program, or why READ would refuse it.
pub fn from_hex(bytes: &[u8]) -> Result<String, String> {
    listing::from_hex(bytes)
        .map(|prog| listing::print(&prog))
        .map_err(|e| format!("not a program READ would take: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn problems_are_the_kits_as_json_and_a_good_listing_has_none() {
        let text = "A0.\n.Y0\nBLAH\nEND\n";
        let json: serde_json::Value = serde_json::from_slice(&problems_json(&check(text))).unwrap();
        let kit = listing::parse("x", text).unwrap_err().problems;
        assert_eq!(json[0]["line"], 3);
        assert_eq!(json[0]["message"], kit[0].message.as_str());
        assert_eq!(json.as_array().unwrap().len(), kit.len());
        assert_eq!(problems_json(&check("A0.\n.Y0\nEND\n")), b"[]");
    }

    #[test]
    fn a_listing_goes_to_hex_and_back() {
        let hex = to_hex("A0.\n.Y0\nEND\nT0 = 50\n").unwrap();
        assert_eq!(
            from_hex(&hex).unwrap(),
            "000 A0.\n001 .Y0\n002 END\nT0 = 50\n"
        );
        assert!(to_hex("BLAH\n").is_err());
        let why = from_hex(b":00000001FF\n").unwrap_err();
        assert!(why.starts_with("not a program READ would take"), "{why}");
    }
}
