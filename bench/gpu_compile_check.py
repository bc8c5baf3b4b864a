"""Compile the GPU batch's kernels for a real GPU target on a machine without a GPU.

    python bench/gpu_compile_check.py [--cc 9.0] [TEST ...]

numba's CUDA simulator (the tests' GPU) runs the kernels as Python: it never types them,
so code that the simulator runs can still fail numba-cuda's compiler on a real GPU. This
script closes that gap before a lent GPU's minutes are spent on it:

1. runs the GPU tests (default tests/dem/gpu) under the simulator with every kernel launch
   of ``Batch._launch`` recorded: the contact law and the numba types of its arguments;
2. in a fresh process without the simulator, compiles each distinct (law, kernel, types)
   to PTX for compute capability --cc with numba-cuda's ``compile_ptx`` (its NVVM needs
   no GPU), and prints one line per kernel: compiled (with ptxas' registers, stack and
   spills where the toolkit wheel has ptxas), or the compiler's error.

Needs numba-cuda with its toolkit wheels (``pip install -e '.[cuda]'``). Exit 1 if any
kernel fails to compile. A check that the code compiles, not that it is right: the
simulator tests say that.
"""
import argparse
import os
import pickle
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
RECORD = "BALLASTSTUDY_GPU_LAUNCHES"


def pytest_configure(config):
    """pytest plugin (``-p gpu_compile_check``): record every launch of the batch."""
    path = os.environ.get(RECORD)
    if not path:
        return
    import numba
    import numpy as np

    from ballaststudy.dem.gpu import batch as B

    seen = set()
    launch = B.Batch._launch

    def typed(a):
        a = getattr(a, "_ary", a)           # the simulator's device array: its ndarray
        return numba.typeof(np.asarray(a) if hasattr(a, "__array_interface__") else a)

    def recording(self, name, n, *args):
        key = (self.law, name, tuple(typed(a) for a in args))
        if key not in seen:
            seen.add(key)
            with open(path, "ab") as f:
                pickle.dump(key, f)
        return launch(self, name, n, *args)

    B.Batch._launch = recording


def record(tests):
    path = Path(tempfile.mkdtemp()) / "launches.pkl"
    env = dict(os.environ, **{RECORD: str(path)}, NUMBA_ENABLE_CUDASIM="1",
               PYTHONPATH=os.pathsep.join([str(HERE), os.environ.get("PYTHONPATH", "")]))
    rc = subprocess.call([sys.executable, "-m", "pytest", "-q", "-n", "0", "-p",
                          "gpu_compile_check", "-o", "addopts=--import-mode=importlib",
                          *tests], cwd=ROOT, env=env)
    if rc != 0:
        print(f"the simulator tests failed (rc {rc}); compiling what they launched", flush=True)
    return path


def compile_all(path, cc):
    """In this process (no simulator): compile each recorded launch to PTX."""
    from numba import cuda
    from numba.cuda import dispatcher

    from ballaststudy.dem.gpu import kernels as K

    class Target:                  # a non-inline device function asks the current device
        compute_capability = cc    # for its target when a kernel calls it: no GPU here
    dispatcher.get_current_device = lambda: Target
    keys = []
    with open(path, "rb") as f:
        while True:
            try:
                keys.append(pickle.load(f))
            except EOFError:
                break
    failed = 0
    done = set()
    for law, name, types in keys:
        if (law, name, types) in done:
            continue
        done.add((law, name, types))
        fn = K.kernels(law)[name].py_func
        t = time.perf_counter()
        try:
            ptx, _ = cuda.compile_ptx(fn, types, cc=cc)
            print(f"ok   {name} (law {hash(law) & 0xffff:04x}): {len(ptx) // 1024} kB PTX "
                  f"in {time.perf_counter() - t:.1f} s{resources(ptx, cc)}", flush=True)
        except Exception as exc:
            failed += 1
            msg = str(exc).strip().splitlines()
            print(f"FAIL {name} (law {hash(law) & 0xffff:04x}): {type(exc).__name__}: "
                  + "\n     ".join(msg[:40]), flush=True)
    print(f"{len(done)} kernel signatures, {failed} failed to compile for cc {cc}")
    return failed


def resources(ptx, cc):
    """'; registers, stack, spills' as ptxas (the toolkit wheel's, if there) reports
    them for the kernel: what the occupancy and local-memory traffic will be."""
    exe = shutil.which("ptxas")
    try:
        from nvidia import cuda_nvcc
        exe = exe or str(Path(cuda_nvcc.__path__[0]) / "bin" / "ptxas")
    except ImportError:
        pass
    if not exe or not Path(exe).exists():
        return ""
    with tempfile.NamedTemporaryFile("w", suffix=".ptx") as f:
        f.write(ptx)
        f.flush()
        out = subprocess.run([exe, f"-arch=sm_{cc[0]}{cc[1]}", "-v", f.name, "-o", os.devnull],
                             capture_output=True, text=True).stderr
    regs = re.search(r"Used (\d+) registers", out)
    frame = re.search(r"(\d+) bytes stack frame, (\d+) bytes spill stores, (\d+) bytes spill loads", out)
    if not regs:
        return "; ptxas: " + out.strip().splitlines()[-1] if out.strip() else ""
    return (f"; {regs.group(1)} registers" + (f", stack {frame.group(1)} B, spills "
            f"{frame.group(2)}/{frame.group(3)} B" if frame else ""))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("tests", nargs="*", default=["tests/dem/gpu"])
    ap.add_argument("--cc", default="9.0")
    ap.add_argument("--launches", help=argparse.SUPPRESS)    # the compiling child's
    a = ap.parse_args(argv)
    cc = tuple(int(x) for x in a.cc.split("."))
    if a.launches:
        return 1 if compile_all(a.launches, cc) else 0
    path = record(a.tests)
    env = dict(os.environ)
    env.pop("NUMBA_ENABLE_CUDASIM", None)
    return subprocess.call([sys.executable, __file__, "--cc", a.cc, "--launches", str(path)],
                           cwd=ROOT, env=env)


if __name__ == "__main__":
    sys.exit(main())
