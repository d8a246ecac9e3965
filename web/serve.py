#!/usr/bin/env python3
"""Serves web/dist/ on http://127.0.0.1:8000/ cross-origin isolated (COOP/COEP headers), so
that the page runs the core on threads; `python3 -m http.server` serves it without them (the
page then runs the core on one thread). Usage: python3 web/serve.py [PORT]"""
import functools
import http.server
import pathlib
import sys


class Isolated(http.server.SimpleHTTPRequestHandler):
    def end_headers(self):
        self.send_header("Cross-Origin-Opener-Policy", "same-origin")
        self.send_header("Cross-Origin-Embedder-Policy", "require-corp")
        super().end_headers()


if __name__ == "__main__":
    port = int(sys.argv[1]) if len(sys.argv) > 1 else 8000
    dist = pathlib.Path(__file__).resolve().parent / "dist"
    handler = functools.partial(Isolated, directory=str(dist))
    with http.server.ThreadingHTTPServer(("127.0.0.1", port), handler) as server:
        print(f"serving {dist} on http://127.0.0.1:{port}/ (cross-origin isolated)")
        server.serve_forever()
