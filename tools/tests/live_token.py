#!/usr/bin/env python3
"""The page beyond loopback asks for its token, in a real browser, for tools/tests/live_guard.rs.

    live_token.py --url http://127.0.0.1:PORT --printed URL

`utile live --http 0.0.0.0:PORT` (reached through 127.0.0.1 only) on the virtual Nano, the
tank with `U0. .Y2`. Headless Chromium through Playwright, as live_page.py drives it: the page
opened without the token says in words what to do and shows no plant; a wrong token is
refused in words; the printed URL pasted in is taken (the cookie set), the plant shows, and a
click on U0 drives Y2 through the program; a new page in the same browser needs nothing more.

Exits 1 with the reason on the first check that fails; prints `ALL OK` at the end.
"""

import argparse

from playwright.sync_api import sync_playwright

# The browser's flags, the longest wait and the reporting are live_page.py's (beside this).
from live_page import ARGS, T, fail, step


def sel(unit, signal):
    return f'.card[data-unit="{unit}"] [data-signal="{signal}"]'


def wait_value(page, unit, signal, want):
    try:
        page.wait_for_function(
            "([s, w]) => { const e = document.querySelector(s); return e && e.dataset.value === w; }",
            arg=[sel(unit, signal), str(want)],
            timeout=T,
        )
    except Exception:
        e = page.query_selector(sel(unit, signal))
        got = e.get_attribute("data-value") if e else None
        fail(f"uTile {unit}: {signal} is {got!r}, not {want!r} after {T} ms")


def wait_text(page, selector, text):
    try:
        page.wait_for_function(
            "([s, t]) => { const e = document.querySelector(s); return e && e.textContent.includes(t); }",
            arg=[selector, text],
            timeout=T,
        )
    except Exception:
        e = page.query_selector(selector)
        fail(f"{selector} does not say {text!r}: it says {e.text_content() if e else None!r}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--url", required=True)
    ap.add_argument("--printed", required=True)
    a = ap.parse_args()
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path="/usr/bin/chromium", args=ARGS)
        context = browser.new_context(viewport={"width": 1300, "height": 1000})
        page = context.new_page()
        errors = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        dialogs = []
        page.on("dialog", lambda d: (dialogs.append(d.message), d.dismiss()))

        step("without the token the page says what to do, and shows no plant")
        page.goto(a.url)
        wait_text(page, "#token-form", "needs its token")
        said = page.text_content("#token-form")
        for words in ["Open the URL it printed", "?token=", "paste the token"]:
            if words not in said:
                fail(f"the request does not say {words!r}: {said!r}")
        wait_text(page, "#mode", "needs its token")
        if page.query_selector(".card"):
            fail("a card shows without the token")
        if dialogs:
            fail(f"the page asked in a dialog box, not in the page: {dialogs}")

        step("a wrong token is refused in words")
        page.fill("#token-input", "0123456789abcdef0123456789abcdef")
        page.click("#token-form button")
        wait_text(page, "#token-error", "refused that token")
        if any(c["name"] == "utile_token" for c in context.cookies()):
            fail("a wrong token was kept in the cookie")
        if page.query_selector(".card"):
            fail("a card shows after a wrong token")

        step("the printed URL pasted in is taken: the plant shows")
        page.fill("#token-input", a.printed)
        page.click("#token-form button")
        wait_value(page, 1, "online", 1)
        wait_value(page, 1, "A6", 409)
        if page.query_selector("#token-form"):
            fail("the request still shows with the plant")
        if not any(c["name"] == "utile_token" for c in context.cookies()):
            fail("no utile_token cookie after the token was taken")

        step("a write works: U0 clicked drives Y2 through the program")
        wait_value(page, 1, "Y2", 0)
        page.click(sel(1, "U0"))
        wait_value(page, 1, "Y2", 1)
        page.click(sel(1, "U0"))
        wait_value(page, 1, "Y2", 0)

        step("another page of the same browser has the token already")
        other = context.new_page()
        other.goto(a.url)
        wait_value(other, 1, "online", 1)
        if other.query_selector("#token-form"):
            fail("the second page asks for the token again")

        if errors:
            fail(f"the page's scripts failed: {errors}")
        browser.close()
    print("ALL OK", flush=True)


if __name__ == "__main__":
    main()
