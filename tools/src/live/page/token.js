// Beyond loopback utile live wants its token (docs/LIVE.md, "Security", "Beyond loopback"): the
// URL printed at its start brings it once (the server keeps it in a cookie); without it the
// page says what to do and takes the token (or that whole URL) pasted in. The token is checked
// by GET /api/token?token=…, which sets the same cookie as the printed URL when it is right;
// a wrong one is said in words.

import { el, errorText } from "/dom.js";

let form = null;

// The token in what was pasted: the token alone, or the printed URL that ends in ?token=….
export function tokenOf(text) {
  const t = text.trim();
  const m = t.match(/[?&]token=([^&#\s]*)/);
  return m ? decodeURIComponent(m[1]) : t;
}

// Checks `token` with the server; true when it took it (the cookie is set), else the words
// of the refusal.
async function offer(token) {
  try {
    const res = await fetch(`/api/token?token=${encodeURIComponent(token)}`);
    if (res.ok) return true;
    if (res.status === 401) {
      return "utile live refused that token: it is not the one it printed at its start " +
        "(the part after ?token= in its URL). Check it and paste it again.";
    }
    return await errorText(res);
  } catch (e) {
    return `the server did not answer (${e}): is utile live still running?`;
  }
}

// Shows the request for the token (once); `why` says what was refused, if anything.
export function askToken(why) {
  if (form) {
    if (why) form.querySelector(".token-why").textContent = why;
    form.querySelector("input").focus();
    return;
  }
  const input = el("input", {
    id: "token-input",
    type: "text",
    autocomplete: "off",
    spellcheck: "false",
    placeholder: "the token, or the whole URL utile live printed",
    "aria-label": "the token",
  });
  const said = el("p", { id: "token-error", class: "token-error", role: "alert" });
  form = el(
    "form",
    { id: "token-form", class: "token-form" },
    el("h2", { text: "This utile live needs its token" }),
    el("p", {
      text:
        "It listens beyond its computer, so reading the plant and every write need the " +
        "token it printed when it started. Open the URL it printed (it ends in ?token=…), " +
        "or paste the token or that whole URL here:",
    }),
    el("p", { class: "token-why", text: why || "" }),
    el("div", { class: "token-row" }, input, el("button", { type: "submit", text: "Use this token" })),
    said,
  );
  form.addEventListener("submit", async (e) => {
    e.preventDefault();
    const token = tokenOf(input.value);
    if (!token) {
      said.textContent = "Paste the token first.";
      return;
    }
    said.textContent = "checking…";
    const answer = await offer(token);
    if (answer === true) {
      // The cookie is set: the page starts again with it.
      location.replace("/");
    } else {
      said.textContent = answer;
      input.select();
    }
  });
  document.querySelector("main").prepend(form);
  input.focus();
}
