#!/usr/bin/env python3
"""Opens HTML reports in headless Chromium and checks what a reader would see.

Usage: tests/browser_check.py [--screenshots DIR] REPORT.html...

For each page, through the DevTools protocol on a pipe (--remote-debugging-pipe: no port,
no extra package), it fails on
  - a console error, an uncaught exception or a browser log error;
  - a request for anything but the page itself and data: URIs (a report must be one
    self-contained file);
  - an image that does not decode (every <img> must have loaded with a width), or a blank one
    (more than 99.9% of its pixels one colour);
  - a blank first screen (a screenshot whose pixels are nearly all one colour);
  - a sortable table whose click does not sort, or a plot that draws nothing.
Screenshots (the first screen, and the whole page at half scale) go to DIR when given.
Exit status: 0 all pass, 1 a check failed, 77 no Chromium (the test then skips).
"""
import base64
import fcntl
import json
import os
import resource
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import zlib


def find_chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


class Browser:
    def __init__(self, binary, profile):
        # fd 3: commands to the browser; fd 4: its replies and events.
        # The pipes are moved above fd 9 first: where the test runs with stdin, stdout or
        # stderr closed (as a CI runner may), os.pipe() hands out 0, 1 or 2, which Popen then
        # overwrites with /dev/null before child_fds runs, and the browser reads an empty pipe.
        def high(fd):
            moved = fcntl.fcntl(fd, fcntl.F_DUPFD_CLOEXEC, 10)
            os.close(fd)
            return moved

        to_browser_r, self.to_browser = (high(fd) for fd in os.pipe())
        self.from_browser, from_browser_w = (high(fd) for fd in os.pipe())
        os.set_inheritable(to_browser_r, True)
        os.set_inheritable(from_browser_w, True)
        self.log_path = os.path.join(profile, "chromium-stderr.log")
        log = open(self.log_path, "wb")

        def child_fds():
            os.dup2(to_browser_r, 3)
            os.dup2(from_browser_w, 4)
            # The browser is a tool here, not the code under test: it reserves far more address
            # space than the suite's soft limit (scripts/pp5 test runs under ulimit -S -v 4 GiB)
            # allows, so its soft limit goes back up to the hard one.
            soft, hard = resource.getrlimit(resource.RLIMIT_AS)
            if soft != hard:
                resource.setrlimit(resource.RLIMIT_AS, (hard, hard))

        self.proc = subprocess.Popen(
            [binary, "--headless=new", "--remote-debugging-pipe", "--no-sandbox",
             "--disable-gpu", "--no-first-run", "--no-default-browser-check",
             "--disable-extensions", "--disable-background-networking",
             "--disable-component-update", "--disable-sync", "--hide-scrollbars",
             f"--user-data-dir={profile}", "about:blank"],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=log,
            preexec_fn=child_fds, close_fds=False)
        log.close()
        os.close(to_browser_r)
        os.close(from_browser_w)
        self.buffer = b""
        self.next_id = 0
        self.events = []

    def stderr_tail(self, lines=20):
        try:
            with open(self.log_path, "rb") as f:
                text = f.read().decode("utf-8", "replace").splitlines()
        except OSError as e:
            return f"(no log: {e})"
        return "\n".join(text[-lines:]) or "(nothing)"

    def close(self):
        try:
            self.send("Browser.close", timeout=5)
        except Exception:
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()

    def _read_message(self, deadline):
        import select
        while b"\0" not in self.buffer:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError("the browser did not answer in time")
            ready, _, _ = select.select([self.from_browser], [], [], left)
            if not ready:
                continue
            chunk = os.read(self.from_browser, 1 << 20)
            if not chunk:
                raise RuntimeError("the browser closed its pipe; its last words:\n" +
                                   self.stderr_tail())
            self.buffer += chunk
        message, self.buffer = self.buffer.split(b"\0", 1)
        return json.loads(message)

    def send(self, method, params=None, session=None, timeout=60):
        self.next_id += 1
        message = {"id": self.next_id, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = session
        data = json.dumps(message).encode() + b"\0"
        while data:
            data = data[os.write(self.to_browser, data):]
        deadline = time.monotonic() + timeout
        while True:
            reply = self._read_message(deadline)
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply.get("result", {})
            self.events.append(reply)

    def wait_event(self, method, timeout=60):
        deadline = time.monotonic() + timeout
        while True:
            for k, e in enumerate(self.events):
                if e.get("method") == method:
                    return self.events.pop(k)
            self.events.append(self._read_message(deadline))


def decode_png(data):
    """The pixels of an 8-bit RGB or RGBA PNG as (width, height, channels, rows)."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, width = 8, b"", 0
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert depth == 8 and colour in (2, 6) and interlace == 0, "unexpected PNG form"
            channels = 3 if colour == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, prev = [], bytearray(stride)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - channels] if x >= channels else 0
            b = prev[x]
            c = prev[x - channels] if x >= channels else 0
            if f == 1:
                line[x] = (line[x] + a) & 255
            elif f == 2:
                line[x] = (line[x] + b) & 255
            elif f == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        prev = line
    return width, height, channels, rows


def blank_share(png):
    """The share of the screenshot's pixels that have its commonest colour."""
    width, height, channels, rows = decode_png(png)
    counts = {}
    for row in rows[::4]:
        for x in range(0, width * channels, channels * 4):
            key = row[x:x + 3]
            counts[key] = counts.get(key, 0) + 1
    return max(counts.values()) / sum(counts.values())


CHECK_PAGE = r"""
(async () => {
  const out = {images: [], text: document.body.innerText.length,
               sections: Array.from(document.querySelectorAll('section')).map(s => {
                 const r = s.getBoundingClientRect();
                 return {id: s.id, x: r.left + window.scrollX, y: r.top + window.scrollY,
                         width: r.width, height: r.height};
               })};
  for (const img of Array.from(document.images)) {
    let ok = true;
    try { await img.decode(); } catch (e) { ok = false; }
    ok = ok && img.complete && img.naturalWidth > 0;
    // Blank or not: the share of its pixels that have its commonest colour, drawn at its
    // natural size (a data: image leaves the canvas readable).
    let share = null, error = null;
    if (ok) {
      try {
        const canvas = document.createElement('canvas');
        canvas.width = img.naturalWidth;
        canvas.height = img.naturalHeight;
        const context = canvas.getContext('2d');
        context.fillStyle = '#ffffff';
        context.fillRect(0, 0, canvas.width, canvas.height);
        context.drawImage(img, 0, 0);
        const data = context.getImageData(0, 0, canvas.width, canvas.height).data;
        const counts = new Map();
        for (let i = 0; i < data.length; i += 4) {
          const key = (data[i] << 16) | (data[i + 1] << 8) | data[i + 2];
          counts.set(key, (counts.get(key) || 0) + 1);
        }
        share = Math.max(...counts.values()) / (data.length / 4);
      } catch (e) { error = String(e); }
    }
    out.images.push({alt: img.alt, ok: ok, width: img.naturalWidth, share: share, error: error});
  }
  return JSON.stringify(out);
})()
"""

INTERACT = r"""
(() => {
  const out = {sorted: null, plots: 0, plotMarks: 0};
  const table = Array.from(document.querySelectorAll('table.report'))
      .find(t => t.tBodies[0].rows.length > 2 && t.querySelector('td[data-n]'));
  if (table) {
    const col = Array.from(table.tBodies[0].rows[0].cells).findIndex(td => td.hasAttribute('data-n'));
    const values = () => Array.from(table.tBodies[0].rows)
        .map(r => parseFloat(r.cells[col].getAttribute('data-n'))).filter(v => !isNaN(v));
    table.tHead.rows[0].cells[col].click();
    const v = values();
    out.sorted = v.every((x, i) => i === 0 || v[i - 1] <= x);
  }
  for (const plot of Array.from(document.querySelectorAll('div.plot'))) {
    out.plots += 1;
    out.plotMarks += plot.querySelectorAll('svg circle').length;
  }
  return JSON.stringify(out);
})()
"""


def check_page(browser, path, shots):
    failures = []
    target = browser.send("Target.createTarget", {"url": "about:blank"})["targetId"]
    session = browser.send("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
    for domain in ("Runtime", "Log", "Page", "Network"):
        browser.send(f"{domain}.enable", session=session)
    browser.send("Emulation.setDeviceMetricsOverride",
                 {"width": 1280, "height": 1000, "deviceScaleFactor": 1, "mobile": False},
                 session=session)
    url = "file://" + os.path.abspath(path)
    browser.send("Page.navigate", {"url": url}, session=session)
    browser.wait_event("Page.loadEventFired", timeout=120)
    result = browser.send("Runtime.evaluate", {"expression": CHECK_PAGE, "awaitPromise": True,
                                               "returnByValue": True}, session=session)
    if "exceptionDetails" in result:
        failures.append(f"the check script failed: {result['exceptionDetails']}")
        facts = {"images": [], "text": 0, "sections": []}
    else:
        facts = json.loads(result["result"]["value"])
    shot = base64.b64decode(browser.send("Page.captureScreenshot", {"format": "png"},
                                         session=session)["data"])
    # Each section on its own (its first 1600 pixels), for a reader to look at.
    section_shots = []
    if shots:
        for sec in facts["sections"]:
            clip = {"x": sec["x"], "y": sec["y"], "width": sec["width"],
                    "height": min(sec["height"], 1600), "scale": 1}
            if clip["width"] > 0 and clip["height"] > 0:
                section_shots.append((sec["id"], base64.b64decode(browser.send(
                    "Page.captureScreenshot", {"format": "png", "captureBeyondViewport": True,
                                               "clip": clip}, session=session)["data"])))
    result = browser.send("Runtime.evaluate", {"expression": INTERACT, "returnByValue": True},
                          session=session)
    if "exceptionDetails" in result:
        failures.append(f"sorting or plotting failed: {result['exceptionDetails']}")
    else:
        facts.update(json.loads(result["result"]["value"]))
    facts.setdefault("sorted", None)
    facts.setdefault("plots", 0)
    facts.setdefault("plotMarks", 0)
    metrics = browser.send("Page.getLayoutMetrics", session=session)
    size = metrics.get("cssContentSize") or metrics["contentSize"]
    full = base64.b64decode(browser.send("Page.captureScreenshot", {
        "format": "png", "captureBeyondViewport": True,
        "clip": {"x": 0, "y": 0, "width": size["width"], "height": min(size["height"], 16000),
                 "scale": 0.5}}, session=session)["data"])
    # Everything the page said or asked for while it loaded and ran.
    for e in browser.events:
        if e.get("sessionId") not in (None, session):
            continue
        method, params = e.get("method"), e.get("params", {})
        if method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
            args = " ".join(str(a.get("value", a.get("description", ""))) for a in params.get("args", []))
            failures.append(f"console error: {args}")
        elif method == "Runtime.exceptionThrown":
            d = params.get("exceptionDetails", {})
            failures.append(f"uncaught exception: {d.get('exception', {}).get('description', d.get('text'))}")
        elif method == "Log.entryAdded" and params.get("entry", {}).get("level") == "error":
            failures.append(f"browser error: {params['entry'].get('text')}")
        elif method == "Network.requestWillBeSent":
            requested = params.get("request", {}).get("url", "")
            if requested != url and not requested.startswith("data:"):
                failures.append(f"requested {requested[:100]}: a report must need nothing outside itself")
    browser.events.clear()
    browser.send("Target.closeTarget", {"targetId": target})
    for img in facts["images"]:
        if not img["ok"]:
            failures.append(f"image '{img['alt']}' does not decode")
        elif img.get("error"):
            failures.append(f"image '{img['alt']}' cannot be read back: {img['error']}")
        elif img["share"] is not None and img["share"] > 0.999:
            failures.append(f"image '{img['alt']}' is blank ({img['share']:.2%} of it one colour)")
    if facts["sorted"] is False:
        failures.append("clicking a numeric heading did not sort its table")
    if facts["plots"] and facts["plotMarks"] == 0:
        failures.append("the plot drew no points")
    share = blank_share(shot)
    if share > 0.97:
        failures.append(f"the first screen is blank ({share:.1%} of it one colour)")
    if shots:
        stem = os.path.join(shots, os.path.splitext(os.path.basename(path))[0] + "-" +
                            os.path.basename(os.path.dirname(os.path.abspath(path))))
        with open(stem + ".png", "wb") as f:
            f.write(shot)
        with open(stem + "-full.png", "wb") as f:
            f.write(full)
        for name, png in section_shots:
            with open(f"{stem}-{name}.png", "wb") as f:
                f.write(png)
    blankest = max((img["share"] or 0 for img in facts["images"]), default=0)
    summary = (f"{len(facts['images'])} images (the blankest {blankest:.1%} one colour), text {facts['text']} characters, "
               f"sorting {'-' if facts['sorted'] is None else 'ok' if facts['sorted'] else 'BROKEN'}, "
               f"{facts['plots']} plots ({facts['plotMarks']} points), first screen "
               f"{share:.0%} one colour")
    return failures, summary


def main():
    args = sys.argv[1:]
    shots = None
    if args[:1] == ["--screenshots"]:
        shots = args[1]
        os.makedirs(shots, exist_ok=True)
        args = args[2:]
    if not args:
        print(__doc__)
        return 2
    binary = find_chromium()
    if not binary:
        print("SKIP: no chromium (scripts/install-deps.sh test installs Debian's chromium)")
        return 77
    hard = resource.getrlimit(resource.RLIMIT_AS)[1]
    if hard != resource.RLIM_INFINITY:
        print(f"FAIL: Chromium cannot start under a hard address-space limit ({hard} bytes, "
              "ulimit -v); set only a soft one (ulimit -S -v), which this check lifts for the "
              "browser")
        return 1
    status = 0
    with tempfile.TemporaryDirectory() as profile:
        browser = Browser(binary, profile)
        try:
            browser.send("Target.setDiscoverTargets", {"discover": False}, timeout=60)
            for path in args:
                failures, summary = check_page(browser, path, shots)
                print(f"{'FAIL' if failures else 'ok  '} {path}: {summary}")
                for f in failures:
                    print(f"     {f}")
                status = status or (1 if failures else 0)
        finally:
            browser.close()
    return status


if __name__ == "__main__":
    sys.exit(main())
