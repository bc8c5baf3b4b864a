"""Keep numba's on-disk cache honest.

numba invalidates a cached function only when ITS OWN source file changes, not when a
kernel it calls (in another module) changes, so editing e.g. contacts.py would leave the
cached ``run_steps`` with the old contact law inlined. At import we hash every module of
this package and drop the package's cache files when the hash differs from the stamp.
"""
import glob
import hashlib
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def refresh():
    h = hashlib.sha256()
    for path in sorted(glob.glob(os.path.join(HERE, "*.py"))):
        with open(path, "rb") as f:
            h.update(f.read())
    digest = h.hexdigest()
    cache = os.path.join(HERE, "__pycache__")
    stamp = os.path.join(cache, "numba_sources.sha256")
    try:
        with open(stamp) as f:
            if f.read().strip() == digest:
                return
    except OSError:
        pass
    try:
        os.makedirs(cache, exist_ok=True)
        for p in glob.glob(os.path.join(cache, "*.nbi")) + glob.glob(os.path.join(cache, "*.nbc")):
            os.unlink(p)
        tmp = stamp + f".{os.getpid()}"
        with open(tmp, "w") as f:
            f.write(digest)
        os.replace(tmp, stamp)
    except OSError:
        pass     # read-only install: numba then compiles in memory / its own cache dir
