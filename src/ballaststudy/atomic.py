"""Atomic file writes: write to a temporary name in the same folder, then rename."""

import contextlib
import os
import shutil
import socket
import uuid
from pathlib import Path


def temporary_name(path):
    """A hidden name beside ``path`` that no other writer picks: on a shared file system
    workers on several hosts may share a pid, so the host and a random part are in it."""
    path = Path(path)
    return path.with_name(f".{path.name}.tmp.{socket.gethostname()}.{os.getpid()}.{uuid.uuid4().hex[:8]}")


@contextlib.contextmanager
def atomic_path(path):
    """Yield a temporary path beside `path`; on success it replaces `path`, on error it is removed."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = temporary_name(path)
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def atomic_copy(src, dst):
    """Copy `src` to `dst` atomically; return `dst`."""
    with atomic_path(dst) as tmp:
        shutil.copyfile(src, tmp)
    return Path(dst)
