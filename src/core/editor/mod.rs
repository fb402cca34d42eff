//! The VT100 screen editor. (Owner: editor work, issue 4.)
