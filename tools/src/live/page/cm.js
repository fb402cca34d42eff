// The listing in CodeMirror 6 (from the npm registry; the page's import map names each of its
// modules): line numbers, undo and the usual keys, uTile's words in the panel's colours (a
// read like `A0.` green as the input lamps, a write like `.Y0` amber as the outputs, comments
// dim), and each problem of the check on its line: the lint gutter's mark (its message on
// hover), the text underlined and the line's number in red. editor.js loads this module the
// first time Edit opens, so the rest of the page never waits for the editor.

import { EditorState, RangeSet, StateEffect, StateField } from "@codemirror/state";
import {
  EditorView, GutterMarker, drawSelection, gutterLineClass, highlightActiveLine,
  highlightActiveLineGutter, keymap, lineNumbers,
} from "@codemirror/view";
import { defaultKeymap, history, historyKeymap } from "@codemirror/commands";
import { HighlightStyle, StreamLanguage, syntaxHighlighting } from "@codemirror/language";
import { lintGutter, setDiagnostics } from "@codemirror/lint";
import { tags } from "@lezer/highlight";

// uTile's listing, word by word (the kit's parser decides what is right; this only colours).
const listing = StreamLanguage.define({
  name: "utile",
  token(stream) {
    if (stream.eatSpace()) return null;
    if (stream.match(/^[#;].*/)) return "comment";
    if (stream.sol() && stream.match(/^\d{3}(?=\s|$)/)) return "labelName"; // a line number
    if (stream.match(/^\.{5}/) || stream.match(/^\$[0-9a-f]{1,2}/i)) return "meta"; // blank, raw byte
    if (stream.match("=")) return "operator";
    if (stream.match(/^\d+/)) return "number";
    if (stream.match(/^\.[^\s#;]+/)) return "propertyName"; // a write: .Y0, .T0
    if (stream.match(/^[^\s#;=.]+\.(?=[\s#;]|$)/)) return "variableName"; // a read: A0., H6.
    stream.match(/^[^\s#;=]+/) || stream.next();
    return "keyword"; // END, KEY, FILL, !, a preset's name
  },
  languageData: { commentTokens: { line: "#" } },
});

const colours = HighlightStyle.define([
  { tag: tags.comment, color: "var(--dim)", fontStyle: "italic" },
  { tag: tags.labelName, color: "var(--dim)" },
  { tag: tags.meta, color: "var(--dim)" },
  { tag: tags.keyword, color: "var(--accent)", fontWeight: "600" },
  { tag: tags.variableName, color: "var(--on)" },
  { tag: tags.propertyName, color: "var(--out)" },
  { tag: tags.number, color: "var(--text)" },
  { tag: tags.operator, color: "var(--dim)" },
]);

// The instrument panel's look, from the page's CSS variables.
const panel = EditorView.theme({
  "&": { height: "100%", color: "var(--text)", backgroundColor: "var(--well)", fontSize: "13px" },
  "&.cm-focused": { outline: "none" },
  ".cm-scroller": { fontFamily: "var(--mono)", lineHeight: "18px" },
  ".cm-content": { caretColor: "var(--accent)" },
  ".cm-cursor, .cm-dropCursor": { borderLeftColor: "var(--accent)" },
  "&.cm-focused > .cm-scroller > .cm-selectionLayer .cm-selectionBackground, .cm-selectionBackground":
    { backgroundColor: "#2b3a55" },
  ".cm-gutters": { backgroundColor: "#171b20", color: "var(--dim)", border: "none",
    borderRight: "1px solid var(--edge)" },
  ".cm-activeLine": { backgroundColor: "#1a1f25" },
  ".cm-activeLineGutter": { backgroundColor: "#1f252c", color: "var(--text)" },
  ".cm-lineNumbers .cm-gutterElement.cm-problem": { color: "#fff", backgroundColor: "var(--warn)",
    borderRadius: "3px" },
  ".cm-tooltip": { backgroundColor: "var(--card)", color: "var(--text)",
    border: "1px solid var(--edge)", fontSize: "12px" },
  ".cm-diagnostic-error": { borderLeftColor: "var(--warn)" },
  ".cm-lintRange-error": { textDecorationColor: "var(--warn)" },
}, { dark: true });

// The lines with a problem, marked on every gutter (the number in red: `.cm-problem`).
const problemMark = new (class extends GutterMarker {
  constructor() {
    super();
    this.elementClass = "cm-problem";
  }
})();
const setProblemLines = StateEffect.define();
const problemLines = StateField.define({
  create: () => RangeSet.empty,
  update(marks, tr) {
    marks = marks.map(tr.changes);
    for (const e of tr.effects) if (e.is(setProblemLines)) marks = e.value;
    return marks;
  },
  provide: (f) => gutterLineClass.from(f),
});

// A listing editor in `parent`; `changed()` is called on every change of the text;
// `attributes` go on the editable element (`.cm-content`).
export function listingEditor(parent, changed, attributes) {
  return new EditorView({
    parent,
    state: EditorState.create({
      extensions: [
        lineNumbers(),
        highlightActiveLineGutter(),
        lintGutter(),
        problemLines,
        history(),
        drawSelection(),
        highlightActiveLine(),
        keymap.of([...defaultKeymap, ...historyKeymap]),
        listing,
        syntaxHighlighting(colours),
        panel,
        EditorView.contentAttributes.of(attributes),
        EditorView.updateListener.of((u) => { if (u.docChanged) changed(); }),
      ],
    }),
  });
}

// The editor's whole text.
export function text(view) {
  return view.state.doc.toString();
}

// Replaces the whole text.
export function setText(view, value) {
  view.dispatch({ changes: { from: 0, to: view.state.doc.length, insert: value } });
}

// Shows `problems` ([{line, message}], lines from 1) on their lines of `doc`, the text they
// were found in; false (nothing shown) when the text has changed since.
export function showProblems(view, doc, problems) {
  if (view.state.doc !== doc) return false;
  const diagnostics = [];
  const marks = [];
  for (const p of problems) {
    const line = doc.line(Math.min(Math.max(p.line, 1), doc.lines));
    const lead = line.text.length - line.text.trimStart().length;
    diagnostics.push({ from: line.from + lead, to: line.from + line.text.trimEnd().length,
      severity: "error", source: "utile asm", message: p.message });
    marks.push(problemMark.range(line.from));
  }
  view.dispatch(setDiagnostics(view.state, diagnostics),
    { effects: setProblemLines.of(RangeSet.of(marks, true)) });
  return true;
}
