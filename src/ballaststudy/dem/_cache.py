"""Keep numba's on-disk cache honest, also on a file system many hosts share.

numba invalidates a cached function only when ITS OWN source file changes, not when a
kernel it calls (in another module) changes, so editing e.g. contacts.py would leave the
cached ``run_steps`` with the old contact law inlined. At import we hash every module of
this package and point numba's cache at a folder of that hash: a changed source is a new
folder, and nothing is deleted that a worker of another version (another host, the same
shared install) may be reading. numba itself keys each entry by the CPU it was compiled
for and writes its files atomically, so hosts of different CPUs share a folder safely.
Folders of other versions not used for ``STALE_DAYS`` are removed.
"""
import glob
import hashlib
import os
import shutil
import time

from numba.core import config

HERE = os.path.dirname(os.path.abspath(__file__))
STALE_DAYS = 14


def sources_digest():
    h = hashlib.sha256()
    for path in sorted(glob.glob(os.path.join(HERE, "*.py"))):
        with open(path, "rb") as f:
            h.update(f.read())
    return h.hexdigest()[:16]


def refresh():
    """Point numba's cache (NUMBA_CACHE_DIR where set, else this package's __pycache__)
    at the folder of this package's sources; call before any kernel is decorated."""
    root = os.path.join(config.CACHE_DIR or os.path.join(HERE, "__pycache__"), "numba-by-source")
    config.CACHE_DIR = os.path.join(root, sources_digest())
    try:
        os.makedirs(config.CACHE_DIR, exist_ok=True)
        os.utime(config.CACHE_DIR)      # its last use: what _remove_stale reads
    except OSError:
        pass        # read-only install: numba falls back to its own cache folders
    _remove_stale(root, config.CACHE_DIR)


def _remove_stale(root, keep):
    try:
        folders = [os.path.join(root, d) for d in os.listdir(root)]
    except OSError:
        return
    old = time.time() - STALE_DAYS * 86400
    for folder in folders:
        try:
            if folder != keep and os.path.getmtime(folder) < old:
                shutil.rmtree(folder, ignore_errors=True)
        except OSError:
            pass        # another host removed it first
