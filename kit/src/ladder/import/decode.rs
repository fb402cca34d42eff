//! A file's bytes as text, for the importers: XML as its byte order mark or its declaration
//! says (UTF-8 with or without BOM, UTF-16 with BOM, `encoding="ISO-8859-1"`,
//! `"windows-1252"`, …), and the text of a Windows program (LDmicro) as UTF-8 when it is,
//! else Windows-1252. The decoding is `encoding_rs`'s.

use std::borrow::Cow;
use std::format;
use std::string::String;

use encoding_rs::{Encoding, UTF_8, WINDOWS_1252};

/// The most of a file's start searched for the XML declaration.
const DECLARATION_BYTES: usize = 1024;

/// An XML document's text: the encoding its BOM names, else the one its declaration
/// names, else UTF-8 (XML's rule). The error says why the bytes are not that text.
pub fn xml_text(bytes: &[u8]) -> Result<Cow<'_, str>, String> {
    if let Some((enc, bom)) = Encoding::for_bom(bytes) {
        return decode(enc, &bytes[bom..]);
    }
    let enc = match declared(bytes) {
        None => UTF_8,
        Some(label) => match Encoding::for_label(label.as_bytes()) {
            // A UTF-16 document has a BOM: the declaration was read as ASCII, so the
            // bytes are not UTF-16 whatever it says (an editor that changed the text and
            // kept the declaration): read them as UTF-8.
            Some(e) if e.output_encoding() == UTF_8 => UTF_8,
            Some(e) => e,
            None => {
                return Err(format!(
                    "file: the XML declares encoding=\"{label}\", which uTile does not know — save it as UTF-8 from the editor"
                ))
            }
        },
    };
    decode(enc, bytes)
}

/// A Windows program's text (LDmicro): UTF-8 with or without BOM when it is valid UTF-8,
/// else Windows-1252 (every byte is a character there, so this never fails).
pub fn utf8_or_windows_1252(bytes: &[u8]) -> Cow<'_, str> {
    let body = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    match std::str::from_utf8(body) {
        Ok(text) => Cow::Borrowed(text),
        Err(_) => WINDOWS_1252.decode_without_bom_handling(body).0,
    }
}

/// The bytes in `enc`, or why not (a byte sequence that encoding has no character for).
fn decode<'b>(enc: &'static Encoding, bytes: &'b [u8]) -> Result<Cow<'b, str>, String> {
    enc.decode_without_bom_handling_and_without_replacement(bytes)
        .ok_or_else(|| {
            if enc == UTF_8 {
                "file: not UTF-8 text — export the program as PLCopen XML (plc.xml) or save it from LDmicro (.ld)".into()
            } else {
                format!(
                    "file: not {} text, though it says so — save it again from the editor",
                    enc.name()
                )
            }
        })
}

/// The `encoding` of an XML declaration at the start of `bytes` (read as ASCII), if any.
fn declared(bytes: &[u8]) -> Option<String> {
    let head = &bytes[..bytes.len().min(DECLARATION_BYTES)];
    let start = head.iter().position(|b| !b.is_ascii_whitespace())?;
    let decl = head[start..].strip_prefix(b"<?xml")?;
    let end = decl.windows(2).position(|w| w == b"?>")?;
    let decl = std::str::from_utf8(&decl[..end]).ok()?;
    let at = decl.find("encoding")?;
    let rest = decl[at + "encoding".len()..].trim_start();
    let rest = rest.strip_prefix('=')?.trim_start();
    let quote = rest.chars().next().filter(|c| *c == '"' || *c == '\'')?;
    let value = &rest[1..];
    let close = value.find(quote)?;
    Some(value[..close].trim().into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_declaration_or_the_bom_chooses_the_encoding() {
        let latin = b"<?xml version=\"1.0\" encoding=\"ISO-8859-1\"?><a>\xE9\xB0</a>";
        assert_eq!(
            xml_text(latin).unwrap(),
            "<?xml version=\"1.0\" encoding=\"ISO-8859-1\"?><a>é°</a>"
        );
        let utf16: std::vec::Vec<u8> = "\u{feff}<a>µ</a>"
            .encode_utf16()
            .flat_map(u16::to_le_bytes)
            .collect();
        assert_eq!(xml_text(&utf16).unwrap(), "<a>µ</a>");
        assert_eq!(xml_text(b"\xEF\xBB\xBF<a/>").unwrap(), "<a/>");
        assert!(xml_text(b"<a>\xE9</a>").unwrap_err().contains("not UTF-8"));
        assert!(xml_text(b"<?xml encoding='klingon'?><a/>")
            .unwrap_err()
            .contains("klingon"));
        assert_eq!(utf8_or_windows_1252(b"x \xB5s \x80"), "x µs €");
        assert_eq!(utf8_or_windows_1252("é".as_bytes()), "é");
    }
}
