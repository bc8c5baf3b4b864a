"""BLAS threads and the loop's Gaussian-process fits (tests/conftest.py's one thread per
test worker): the loop's judgement of its three candidates on test_select's fresh-specimen
control (seed 1), with OpenBLAS's and OpenMP's threads as they come and limited to one,
alternately in one invocation. Run it alone, then beside a busy core (as a test worker runs
beside the other):

    python bench/blas_threads.py
    (python -c "while True: pass" &) ; python bench/blas_threads.py ; pkill -f "while True"
"""
import sys
import time
from pathlib import Path

from threadpoolctl import threadpool_info, threadpool_limits

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests.loop.test_select import _loop_fresh  # noqa: E402


def main(rounds=2):
    print("thread pools:", [(i["internal_api"], i["num_threads"]) for i in threadpool_info()])
    for _ in range(rounds):
        for limit in (None, 1):
            t = time.perf_counter()
            with threadpool_limits(limit):
                _loop_fresh(None, 1)
            print(f"threads {limit or 'as they come'}: {time.perf_counter() - t:.2f} s")


if __name__ == "__main__":
    main()
