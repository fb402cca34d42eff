//! `POST /api/check` with `{"listing": "…"}`: the listing checked by the kit's own parser
//! (the one `utile asm` uses), each problem with its line, so the page's editor shows the
//! same messages `utile asm` gives while the user types. Nothing goes on the line: checking
//! works with `--read-only` too.

use axum::extract::rejection::JsonRejection;
use axum::Json;
use serde::{Deserialize, Serialize};

use utile_kit::listing;

use super::api::ApiError;

/// `POST /api/check`'s body.
#[derive(Debug, Deserialize)]
pub struct CheckBody {
    /// The listing's text, as a `.utl` file holds it.
    #[serde(default)]
    pub listing: String,
}

/// One problem of a listing, at a 1-based line of its text.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Problem {
    /// The text's line, 1-based.
    pub line: usize,
    /// What is wrong, in `utile asm`'s words.
    pub message: String,
}

/// The problems of `text` (none when it is a good listing): the kit's [`listing::check`].
pub fn problems(text: &str) -> Vec<Problem> {
    listing::check(text)
        .into_iter()
        .map(|p| Problem {
            line: p.line,
            message: p.message,
        })
        .collect()
}

/// `POST /api/check`: 200 with `[{"line", "message"}]`, empty when the listing is good.
pub async fn post(
    body: Result<Json<CheckBody>, JsonRejection>,
) -> Result<Json<Vec<Problem>>, ApiError> {
    let Json(body) = body?;
    Ok(Json(problems(&body.listing)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_good_listing_has_no_problems_and_a_bad_one_says_where() {
        assert!(problems("A0.\n.Y0\nEND\n").is_empty());
        let p = problems("A0.\n.Y0\nBLAH\nEND\n");
        assert_eq!(p.len(), 1);
        assert_eq!(p[0].line, 3);
        // The kit's own words, as `utile asm` prints them after `file:line: `.
        let asm = listing::parse("x", "A0.\n.Y0\nBLAH\nEND\n").unwrap_err();
        assert_eq!(asm.problems[0].message, p[0].message);
    }
}
