"""A folder served over HTTP on this machine, for `fetch` to download from as it would from
the source (CI reaches no repository): the development machines' copy of the source's
experimental_data/ folder, or a copy of it with a file changed."""
import contextlib
import functools
import threading
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

LOCAL_COPY = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "measured"


class _Quiet(SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


@contextlib.contextmanager
def served(folder):
    """The URL of ``folder`` served by a local HTTP server while the block runs."""
    server = ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(_Quiet, directory=str(folder)))
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}/"
    finally:
        server.shutdown()
        server.server_close()
