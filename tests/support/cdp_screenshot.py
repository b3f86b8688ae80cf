#!/usr/bin/python3
"""Opens URL in a new tab of a headless Chromium started with
--remote-debugging-port=PORT, and at the page's load event — the moment
`chromium --headless --screenshot` takes its picture — evaluates EXPR (a
JavaScript expression) and captures the tab (Page.captureScreenshot) into
OUT as PNG, by the DevTools protocol (python3-websocket). Prints EXPR's
value as JSON and exits 0; 1 when the page did not load within SECONDS,
2 on an error. The tab is closed at the end, as in cdp_wait.py, whose
handshake (no Origin header) this one shares.

    cdp_screenshot.py PORT URL OUT SECONDS EXPR
"""
import base64
import json
import sys
import time
import urllib.request

import websocket


class Tab:
    def __init__(self, ws):
        self.ws, self.last_id, self.events = ws, 0, []

    def call(self, method, params=None):
        self.last_id += 1
        self.ws.send(json.dumps({"id": self.last_id, "method": method, "params": params or {}}))
        while True:  # keeps events aside until the answer (bounded by the socket's timeout)
            reply = json.loads(self.ws.recv())
            if reply.get("id") == self.last_id:
                return reply.get("result", {})
            self.events.append(reply.get("method"))

    def wait_for_event(self, method, deadline):
        if method in self.events:  # it came while a call waited for its answer
            return True
        while time.monotonic() < deadline:  # bounded by SECONDS and the socket's timeout
            if json.loads(self.ws.recv()).get("method") == method:
                return True
        return False


def main():
    port, url, out, seconds, expression = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4]), sys.argv[5]
    request = urllib.request.Request(f"http://127.0.0.1:{port}/json/new?about:blank", method="PUT")
    target = json.load(urllib.request.urlopen(request, timeout=10))
    try:
        ws = websocket.create_connection(target["webSocketDebuggerUrl"], timeout=10, suppress_origin=True)
        tab = Tab(ws)
        tab.call("Page.enable")
        tab.call("Page.navigate", {"url": url})
        if not tab.wait_for_event("Page.loadEventFired", time.monotonic() + seconds):
            print(json.dumps("the page did not load"))
            return 1
        value = tab.call("Runtime.evaluate", {"expression": expression, "returnByValue": True})
        shot = tab.call("Page.captureScreenshot", {"format": "png"})
        with open(out, "wb") as f:
            f.write(base64.b64decode(shot["data"]))
        print(json.dumps(value.get("result", {}).get("value")))
        return 0
    finally:
        urllib.request.urlopen(f"http://127.0.0.1:{port}/json/close/{target['id']}", timeout=10).read()


if __name__ == "__main__":
    try:
        sys.exit(main())
    except Exception as error:  # a test reads the reason from the output
        print(f"cdp_screenshot: {error}")
        sys.exit(2)
