// What the card, the program view and the trend share: one element builder, and the words of
// an API failure.

// An element `tag` with its attributes ("class" and "text" set the class and the text) and
// children.
export function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "class") e.className = v;
    else if (k === "text") e.textContent = v;
    else e.setAttribute(k, v);
  }
  e.append(...children);
  return e;
}

// A failed answer's words: the API answers every failure as {"error": "..."}.
export async function errorText(res) {
  try {
    const body = await res.json();
    if (body && typeof body.error === "string") return body.error;
  } catch (e) {
    // Not JSON: said below.
  }
  return `the server answered ${res.status} ${res.statusText}`;
}
