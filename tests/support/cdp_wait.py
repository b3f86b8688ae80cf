#!/usr/bin/python3
"""Opens URL in a new tab of a headless Chromium started with
--remote-debugging-port=PORT and evaluates EXPR (a JavaScript expression)
every 250 ms until it returns a truthy value or SECONDS have passed, by the
DevTools protocol (python3-websocket). Prints the last value as JSON and
exits 0 when it became truthy, 1 when the time ran out, 2 on an error.
The tab is closed at the end: a browser keeps at most six connections to
one server, and a tab left open keeps its event stream's.

The WebSocket handshake sends no Origin header: Chromium refuses (403) one
whose Origin is not allowed by --remote-allow-origins, as Debian 12's
chromium 150 does for websocket-client's default; without the header every
version accepts it (app/view_browser_test.cc checks what is sent).

    cdp_wait.py PORT URL SECONDS EXPR
"""
import json
import sys
import time
import urllib.request

import websocket


def main():
    port, url, seconds, expression = sys.argv[1], sys.argv[2], float(sys.argv[3]), sys.argv[4]
    request = urllib.request.Request(f"http://127.0.0.1:{port}/json/new?{url}", method="PUT")
    target = json.load(urllib.request.urlopen(request, timeout=10))
    try:
        return wait(target, seconds, expression)
    finally:
        urllib.request.urlopen(f"http://127.0.0.1:{port}/json/close/{target['id']}", timeout=10).read()


def wait(target, seconds, expression):
    ws = websocket.create_connection(target["webSocketDebuggerUrl"], timeout=10, suppress_origin=True)
    deadline = time.monotonic() + seconds
    value, message_id = None, 0
    while time.monotonic() < deadline:  # bounded by SECONDS
        message_id += 1
        ws.send(json.dumps({"id": message_id, "method": "Runtime.evaluate",
                            "params": {"expression": expression, "returnByValue": True}}))
        while True:  # skips events until the answer to this request (bounded by the socket's timeout)
            reply = json.loads(ws.recv())
            if reply.get("id") == message_id:
                break
        value = reply.get("result", {}).get("result", {}).get("value")
        if value:
            print(json.dumps(value))
            return 0
        time.sleep(0.25)
    print(json.dumps(value))
    return 1


if __name__ == "__main__":
    try:
        sys.exit(main())
    except Exception as error:  # a test reads the reason from the output
        print(f"cdp_wait: {error}")
        sys.exit(2)
