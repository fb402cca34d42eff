#!/usr/bin/env python3
"""The playground (out/play/) in a real browser, served as a static site by
`python3 -m http.server`, for tools/tests/play_page.rs and `./x play --bench`.

    page.py test  --site out/play --utile target/debug/utile [--screenshot PNG]
    page.py bench --site out/play

Drives Debian's chromium through Playwright (headless) as a user would: types into the
terminal, presses the rig's buttons, fits jumpers, reloads, reads the LEDs by their
data-led / data-on attributes and the screen from xterm.js's buffer. Every request must go to
the site's own origin and no console error may appear.

`test` exits 1 with the reason on the first check that fails and prints `ALL OK` at the end.
`bench` prints the figures of BENCHMARKS.md ("The playground") as `figure: value` lines.
"""

import argparse
import gzip
import json
import os
import socket
import statistics
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

from playwright.sync_api import sync_playwright

ARGS = [
    "--no-sandbox",
    "--headless=new",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]
T = 60_000  # ms: the longest wait for anything the page must show (every wait is for a
# condition, never a sleep; a loaded machine may run the simulation slower than the clock)
REPO = Path(__file__).resolve().parents[2]
EEPROM_KEY = "utile-play-eeprom"

# The program the test types: Y0 lights while A0 is pressed, Y1 while A1 is open; KEY lets
# a lone / stop it.
PROGRAM = ["FILL", "A0.", "!", ".Y0", "A1.", ".Y1", "KEY", "END"]


def fail(why):
    print(f"FAIL: {why}", flush=True)
    sys.exit(1)


def step(what):
    print(f"-- {what}", flush=True)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Server:
    """`python3 -m http.server` on the site, as any static host would serve it."""

    def __init__(self, site):
        self.port = free_port()
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "http.server", "--bind", "127.0.0.1", "--directory",
             str(site), str(self.port)],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        self.origin = f"http://127.0.0.1:{self.port}"
        for _ in range(100):
            try:
                urllib.request.urlopen(self.origin + "/", timeout=2).read()
                return
            except OSError:
                time.sleep(0.1)
        fail("python3 -m http.server did not answer")

    def stop(self):
        self.proc.terminate()
        self.proc.wait(timeout=10)


class Watch:
    """Every request and console error of a browser context."""

    def __init__(self, origin):
        self.origin = origin
        self.foreign = []
        self.errors = []
        self.loaded = {}

    def attach(self, page):
        page.on("request", self.request)
        page.on("console", lambda m: m.type == "error" and self.errors.append(m.text))
        page.on("pageerror", lambda e: self.errors.append(str(e)))
        page.on("response", lambda r: self.loaded.setdefault(r.url, r.status))

    def request(self, req):
        url = req.url
        if not (url.startswith(self.origin + "/") or url.startswith(("data:", "blob:"))):
            self.foreign.append(url)

    def check(self):
        if self.foreign:
            fail(f"requests to another origin: {self.foreign}")
        if self.errors:
            fail(f"console errors: {self.errors}")


class Play:
    """The playground in one page."""

    def __init__(self, page, url):
        self.page = page
        self.url = url

    def open(self, query=""):
        self.page.goto(self.url + "/" + query)

    def screen(self):
        """The terminal's 24 rows as text."""
        return self.page.evaluate(
            """() => { const t = window.utileTerminal; if (!t) return '';
                const b = t.buffer.active; const rows = [];
                for (let y = 0; y < t.rows; y++) {
                  const l = b.getLine(b.viewportY + y); rows.push(l ? l.translateToString(true) : '');
                }
                return rows.join('\\n'); }""")

    def wait_text(self, text, timeout=T):
        """Waits until the terminal shows `text`; the time (performance.now()) it did."""
        try:
            self.page.wait_for_function(
                """(w) => { const t = window.utileTerminal; if (!t) return false;
                    const b = t.buffer.active;
                    for (let y = 0; y < t.rows; y++) {
                      const l = b.getLine(b.viewportY + y);
                      if (l && l.translateToString(true).includes(w)) return true;
                    }
                    return false; }""",
                arg=text, timeout=timeout, polling="raf")
        except Exception:
            fail(f"the terminal does not show {text!r} after {timeout} ms; it shows:\n{self.screen()}")
        return self.page.evaluate("performance.now()")

    def type(self, text):
        """Keys into the terminal, as a user types them."""
        self.page.click("#xterm")
        self.page.keyboard.type(text)

    def enter(self, line, echo=None):
        """Types a line and Enter; waits until the screen shows `echo` (the line's echo)."""
        self.type(line)
        self.page.keyboard.press("Enter")
        if echo:
            self.wait_text(echo)

    def paste(self, text):
        """A paste into the terminal (the browser's paste event, as Ctrl+V makes)."""
        self.page.evaluate(
            """(text) => { const dt = new DataTransfer(); dt.setData('text/plain', text);
                document.querySelector('.xterm-helper-textarea').dispatchEvent(
                  new ClipboardEvent('paste', { clipboardData: dt, bubbles: true, cancelable: true })); }""",
            text)

    def led(self, n):
        return self.page.get_attribute(f'[data-led="Y{n}"]', "data-on")

    def wait_led(self, n, on, timeout=T):
        try:
            self.page.wait_for_function(
                "([n, w]) => document.querySelector(`[data-led=\"Y${n}\"]`).dataset.on === w",
                arg=[n, "1" if on else "0"], timeout=timeout)
        except Exception:
            fail(f"Y{n} is {self.led(n)!r}, not {'on' if on else 'off'} after {timeout} ms; the screen:\n{self.screen()}")

    def rig(self, name):
        return self.page.locator(f'[data-rig="{name}"]')

    def hold(self, name):
        box = self.rig(name).bounding_box()
        self.page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
        self.page.mouse.down()

    def release(self):
        self.page.mouse.up()

    def wait_pending(self):
        """Until every byte typed has gone down the line into the Nano."""
        self.page.wait_for_function("() => window.utilePlay && window.utilePlay.serial.pending === 0",
                                    timeout=T)

    def load_through_read(self, hex_text):
        """READ in the editor, the hex file pasted, the page back."""
        self.enter("READ", "Reading file")
        self.paste(hex_text)
        self.wait_text("File read completed")
        self.page.keyboard.press("Enter")
        self.wait_text("User File 0")

    def storage(self, key):
        return self.page.evaluate("(k) => localStorage.getItem(k)", key)


def run(cmd, **kw):
    return subprocess.run(cmd, capture_output=True, text=True, **kw)


def type_program(p):
    for word in PROGRAM:
        p.enter(word)
    p.wait_pending()


def test_boot_program_rig(p):
    step("boot screen in the terminal")
    p.open()
    p.wait_text("User File 0")
    if "<<<< Nano - u T I L E - ATmega328 >>>>" not in p.screen():
        fail(f"no title on the boot screen:\n{p.screen()}")
    step("a program typed in the terminal, run with EX0")
    type_program(p)
    p.wait_text("END")
    p.enter("EX0", "Running User File Program")
    p.wait_led(1, True)
    p.wait_led(0, False)
    step("the rig: A0 held lights Y0, released puts it out; A1 latched puts Y1 out")
    p.hold("A0")
    p.wait_led(0, True)
    p.release()
    p.wait_led(0, False)
    p.rig("latch").click()
    p.rig("A1").click()
    p.wait_led(1, False)
    if p.rig("A1").get_attribute("data-value") != "1":
        fail("A1 latched does not show pressed")
    p.rig("A1").click()
    p.wait_led(1, True)
    p.rig("latch").click()
    step("the A6 slider moves A6 (volts shown)")
    p.rig("A6").fill("2.5")
    p.page.wait_for_function("() => document.querySelector('[data-rig=\"A6\"]').dataset.value === '2.50'")


def test_store_autostart_erase(p):
    step("/ stops the program, STORE keeps it in the browser's EEPROM")
    p.type("/")
    p.wait_text("Strike any key")
    p.type(" ")
    p.wait_text("User File 0")
    p.enter("STORE", "UF0 stored in EEPROM")
    saved = p.storage(EEPROM_KEY)
    if not saved or set(saved) == {"f"}:
        fail(f"the EEPROM is not in localStorage after STORE: {saved!r}")
    step("D8 fitted, the page reloaded: the stored program autostarts")
    p.rig("D8").click()
    if p.rig("D8").get_attribute("data-value") != "1":
        fail("D8 does not show fitted")
    p.open()
    p.wait_text("Running User File Program")
    p.wait_led(1, True)
    p.hold("A0")
    p.wait_led(0, True)
    p.release()
    p.wait_led(0, False)
    step("Erase EEPROM (two clicks): blank, and with D8 still fitted nothing autostarts")
    erase = p.page.locator('[data-action="erase-eeprom"]')
    erase.click()
    if p.storage(EEPROM_KEY) != saved:
        fail("one click erased the EEPROM (it takes two)")
    erase.click()
    p.wait_text("User File 0")
    p.page.wait_for_function(
        "(k) => /^f{2048}$/.test(localStorage.getItem(k) || '')", arg=EEPROM_KEY, timeout=T)
    p.wait_led(1, False)
    p.open()
    p.wait_text("User File 0")
    if "Running User File Program" in p.screen():
        fail(f"a program autostarted after Erase EEPROM:\n{p.screen()}")
    p.rig("D8").click()


def test_hidden_pauses(p):
    step("a hidden tab pauses the Nano, visible again it goes on")
    p.page.evaluate("""() => { window.__hidden = true;
        Object.defineProperty(document, 'hidden', { configurable: true, get: () => window.__hidden });
        document.dispatchEvent(new Event('visibilitychange')); }""")
    p.page.wait_for_timeout(300)
    a = p.page.evaluate("window.utilePlay.nano.cycles")
    p.page.wait_for_timeout(700)
    b = p.page.evaluate("window.utilePlay.nano.cycles")
    if a != b:
        fail(f"the Nano ran while the tab was hidden ({b - a} cycles)")
    p.page.evaluate("() => { window.__hidden = false; document.dispatchEvent(new Event('visibilitychange')); }")
    p.page.wait_for_function(f"() => window.utilePlay.nano.cycles > {b}", timeout=T)


def examples_on_disk():
    return sorted(str(f.relative_to(REPO / "examples"))[:-4]
                  for f in (REPO / "examples").rglob("*.utl"))


def test_examples(p, utile):
    step("every example listed, its listing shown, its .hex the one utile asm writes")
    p.page.click('[data-tab="examples"]')
    names = p.page.eval_on_selector_all("[data-example]", "es => es.map(e => e.dataset.example)")
    if sorted(names) != examples_on_disk():
        fail(f"the page lists {sorted(names)}, examples/ has {examples_on_disk()}")
    first = p.page.locator('[data-example="tank-fill"]')
    first.locator('[data-action="show"]').click()
    shown = first.locator("pre").text_content()
    if shown != (REPO / "examples/tank-fill.utl").read_text():
        fail("the shown listing is not the file")
    p.page.wait_for_function("() => !document.querySelector('[data-action=\"hex\"]').hasAttribute('aria-disabled')", timeout=T)
    # Every example's .hex as the page makes it (the module's listingToHex on the listing
    # index.json carries, what the .hex link's click runs) against utile asm's file; two of
    # them through the link itself, as downloads (Chromium refuses a tab's eleventh
    # download in quick succession, so not all 23).
    made = p.page.evaluate("""async () => {
        const list = await (await fetch('./examples/index.json')).json();
        return Object.fromEntries(list.map((e) => [e.name, window.utilePlay.utile.listingToHex(e.text).hex]));
        }""")
    with tempfile.TemporaryDirectory() as tmp:
        want = Path(tmp) / "asm.hex"
        for name in names:
            r = run([utile, "asm", str(REPO / "examples" / f"{name}.utl"), "-o", str(want)])
            if r.returncode != 0:
                fail(f"utile asm {name}: {r.stderr}")
            if (made.get(name) or "").encode() != want.read_bytes():
                fail(f"{name}: the page's .hex differs from utile asm's")
        for name in ["tank-fill", "ch5-8/ex07_or"]:
            row = p.page.locator(f'[data-example="{name}"]')
            try:
                with p.page.expect_download(timeout=15_000) as d:
                    row.locator('[data-action="hex"]').click()
            except Exception:
                fail(f"{name}: its .hex did not download")
            got = Path(tmp) / "page.hex"
            d.value.save_as(got)
            if got.read_bytes() != made[name].encode():
                fail(f"{name}: the downloaded .hex is not the one the page makes")
            if d.value.suggested_filename != f"{name.split('/')[-1]}.hex":
                fail(f"{name}: downloaded as {d.value.suggested_filename}")
    p.page.click('[data-tab="nano"]')


def test_module_words(p, utile):
    step("the WebAssembly module: utile asm's messages and utile dis's listing")
    bad = "A0.\n.Y0\nBLAH\nT0 = 300\nC9 = 1\nEND\n"
    with tempfile.TemporaryDirectory() as tmp:
        f = Path(tmp) / "bad.utl"
        f.write_text(bad)
        r = run([utile, "asm", str(f)])
        if r.returncode == 0:
            fail("utile asm took the bad listing")
        want = [line.split(":", 2) for line in r.stderr.splitlines() if line.startswith(str(f))]
        want = [{"line": int(n), "message": m.strip()} for _, n, m in want]
        got = p.page.evaluate("(t) => window.utilePlay.utile.check(t)", bad)
        if got != want or len(got) < 3:
            fail(f"the module's problems {got} are not utile asm's {want}")
        hexfile = REPO / "examples/parts-counter.utl"
        r = run([utile, "asm", str(hexfile), "-o", str(Path(tmp) / "p.hex")])
        dis = run([utile, "dis", str(Path(tmp) / "p.hex")])
        back = p.page.evaluate("(h) => window.utilePlay.utile.hexToListing(h)",
                               (Path(tmp) / "p.hex").read_text())
        if back.get("listing") != dis.stdout:
            fail(f"the module's listing {back} is not utile dis's {dis.stdout!r}")
        broken = p.page.evaluate("() => window.utilePlay.utile.hexToListing(':00000001FE\\n')")
        if "READ" not in broken.get("why", ""):
            fail(f"a damaged hex file is not refused in words: {broken}")


def test_tank(p):
    step("the tank example through READ (pasted), the tank on A6/A7: the pump fills it")
    p.type("/")
    p.wait_text("Strike any key")
    p.type(" ")
    p.wait_text("User File 0")
    hex_text = p.page.evaluate(
        "async () => window.utilePlay.utile.listingToHex(await (await fetch('./examples/tank-fill.utl')).text()).hex")
    p.load_through_read(hex_text)
    p.rig("A6").fill("2")
    p.page.check('[data-plant="tank"]')
    p.enter("EX0", "Running User File Program")
    # At power-up H7 reads 0 until the first readings: the program starts the pump (Y0), and
    # the tank fills from 2 V to the high mark (3.91 V), where the pump stops.
    p.wait_led(0, True)
    start = float(p.rig("A6").get_attribute("data-value"))
    p.page.wait_for_function(
        f"() => Number(document.querySelector('[data-rig=\"A7\"]').dataset.value) > {start + 0.3}",
        timeout=T)
    p.wait_led(0, False)
    level = float(p.rig("A6").get_attribute("data-value"))
    if not 3.7 < level < 4.1:
        fail(f"the pump stopped at {level} V, not at the high mark (3.91 V)")
    p.page.uncheck('[data-plant="tank"]')


def test_narrow(p, browser, watch):
    step("390 px wide: nothing overflows, the terminal and the rig are there")
    ctx = browser.new_context(viewport={"width": 390, "height": 844})
    page = ctx.new_page()
    watch.attach(page)
    q = Play(page, p.url)
    q.open()
    q.wait_text("User File 0")
    width = page.evaluate("() => Math.max(document.documentElement.scrollWidth, document.body.scrollWidth)")
    if width > 390:
        wide = page.evaluate("""() => [...document.querySelectorAll('body *')]
            .filter(e => e.getBoundingClientRect().right > 391).slice(0, 5)
            .map(e => e.tagName + '.' + e.className)""")
        fail(f"the page is {width} px wide at 390: {wide}")
    for sel in ["#xterm", '[data-rig="A0"]', '[data-led="Y7"]', '[data-rig="reset"]']:
        if not page.locator(sel).is_visible():
            fail(f"{sel} is not visible at 390 px")
    ctx.close()


def screenshot(p, path):
    step(f"screenshot {path}")
    p.page.set_viewport_size({"width": 1280, "height": 760})
    p.hold("A0")
    p.wait_led(0, True)
    p.page.screenshot(path=path)
    p.release()


def test(args):
    server = Server(args.site)
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path="/usr/bin/chromium", args=ARGS)
            watch = Watch(server.origin)
            ctx = browser.new_context(viewport={"width": 1280, "height": 900}, accept_downloads=True)
            page = ctx.new_page()
            watch.attach(page)
            p = Play(page, server.origin)
            test_boot_program_rig(p)
            test_hidden_pauses(p)
            test_module_words(p, args.utile)
            test_examples(p, args.utile)
            test_store_autostart_erase(p)
            type_program(p)
            p.enter("EX0", "Running User File Program")
            if args.screenshot:
                screenshot(p, args.screenshot)
            test_tank(p)
            test_narrow(p, browser, watch)
            watch.check()
            browser.close()
    finally:
        server.stop()
    print("ALL OK", flush=True)


# --- figures ----------------------------------------------------------------------------

def long_listing():
    """256 lines: 85 times `An. ! .Yn` over A0..A5/Y0..Y5, then END."""
    words = []
    for k in range(85):
        n = k % 6
        words += [f"A{n}.", "!", f".Y{n}"]
    return "\n".join(words + ["END"]) + "\n"


def bench(args):
    server = Server(args.site)
    figures = {}
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path="/usr/bin/chromium", args=ARGS)
            watch = Watch(server.origin)
            ctx = browser.new_context(viewport={"width": 1280, "height": 900})
            page = ctx.new_page()
            watch.attach(page)
            p = Play(page, server.origin)

            boots = []
            for _ in range(3):
                p.open()
                boots.append(p.wait_text("User File 0"))
            figures["load average (1 min) at the start"] = os.getloadavg()[0]
            figures["boot screen after the page starts loading, 3 loads (ms)"] = [round(b) for b in boots]
            files = [u for u in watch.loaded if u.startswith(server.origin)]
            raw = zipped = 0
            for u in files:
                rel = u[len(server.origin) + 1:].split("?")[0] or "index.html"
                data = (Path(args.site) / rel).read_bytes()
                raw += len(data)
                zipped += len(gzip.compress(data, 6))
            figures["first load: files"] = len(files)
            figures["first load (KiB, raw)"] = round(raw / 1024)
            figures["first load (KiB, gzip -6)"] = round(zipped / 1024)
            figures["CodeMirror loaded"] = any("codemirror" in u for u in files)

            step("the 256-line program through READ, then RUN")
            hex_text = page.evaluate("(t) => window.utilePlay.utile.listingToHex(t).hex", long_listing())
            p.load_through_read(hex_text)
            p.enter("EX0", "Running User File Program")
            page.wait_for_timeout(5000)
            figures["paced speed in RUN, 256 lines (x real time)"] = float(
                page.get_attribute("[data-sim-speed]", "data-value"))

            step("rig press to LED")
            times = page.evaluate("""async () => {
                const out = [];
                const led = document.querySelector('[data-led="Y0"]');
                const b = document.querySelector('[data-rig="A0"]');
                for (let i = 0; i < 20; i++) {
                  const want = led.dataset.on === '1' ? '0' : '1';
                  const t0 = performance.now();
                  const seen = new Promise((ok) => {
                    const o = new MutationObserver(() => { if (led.dataset.on === want) { o.disconnect(); ok(); } });
                    o.observe(led, { attributes: true });
                  });
                  b.dispatchEvent(new PointerEvent(want === '1' ? 'pointerdown' : 'pointerup',
                    { button: 0, pointerId: 1, bubbles: true }));
                  await seen;
                  out.push(performance.now() - t0);
                  await new Promise((ok) => setTimeout(ok, 60));
                }
                return out; }""")
            figures["rig press to LED, median (ms)"] = round(statistics.median(times), 1)
            figures["rig press to LED, max (ms)"] = round(max(times), 1)

            step("unpaced")
            p.open("?speed=max")
            p.wait_text("User File 0")
            p.load_through_read(hex_text)
            p.enter("EX0", "Running User File Program")
            page.wait_for_timeout(1000)
            # The page's main thread's CPU time (Chromium's ThreadTime) beside the wall clock:
            # on a machine other work shares, the first says what a free core would give.
            cdp = ctx.new_cdp_session(page)
            cdp.send("Performance.enable")

            def sample():
                m = {x["name"]: x["value"] for x in cdp.send("Performance.getMetrics")["metrics"]}
                return m["ThreadTime"], time.monotonic(), page.evaluate("window.utilePlay.nano.cycles")

            cpu0, wall0, c0 = sample()
            page.wait_for_timeout(5000)
            cpu1, wall1, c1 = sample()
            x = float(page.get_attribute("[data-sim-speed]", "data-value"))
            figures["unpaced speed in RUN, 256 lines (x real time)"] = x
            figures["unpaced, simulated MHz per wall second"] = round((c1 - c0) / (wall1 - wall0) / 1e6, 1)
            figures["unpaced, simulated MHz per CPU second of the page's thread"] = round(
                (c1 - c0) / (cpu1 - cpu0) / 1e6, 1)
            figures["load average (1 min) at the end"] = os.getloadavg()[0]
            watch.check()
            browser.close()
    finally:
        server.stop()
    for k, v in figures.items():
        print(f"{k}: {v}", flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("what", choices=["test", "bench"])
    ap.add_argument("--site", default=str(REPO / "out/play"))
    ap.add_argument("--utile", default=str(REPO / "target/debug/utile"))
    ap.add_argument("--screenshot")
    args = ap.parse_args()
    if not (Path(args.site) / "index.html").is_file():
        fail(f"{args.site} has no playground: run ./x play --build")
    test(args) if args.what == "test" else bench(args)


if __name__ == "__main__":
    main()
