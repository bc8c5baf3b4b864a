#!/bin/bash
# The prepared run on a lent GPU machine (../.library/device): issue 33's figures in one call.
#
#   bash bench/gpu_lease.sh [STEP ...]   (on the device machine, from the repository root)
#
# STEPs (default: all, in this order): rigs_biaxial, calibrate_cuda, rigs_box, ensemble,
# tests_real_gpu. The 2026-11-27 lease's figures: bench/gpu_notes.md. There calibrate_cuda
# needed more than its 140 s (cold compiles: one case of 12 written at 94 s); a lease that
# runs it alone gives it LIMIT_calibrate_cuda=400 (each step's limit: LIMIT_<step>).
#
# Expects, made beforehand on a CPU machine and carried with the call (.git/info/exclude
# ignores both):
#   .whl/       wheels of the packages the device image lacks (cftime, netCDF4, jsonschema
#               and its three, shapely, trimesh; Python 3.12, manylinux x86-64);
#   .devcarry/  biaxial_full.nc and box_thesis.nc (bench/gpu_rigs.py --assemble-only: the
#               full-size biaxial specimen of config.yaml, the box case of thesis.yaml),
#               their runs after cycle 0 (*_c0.npz: gpu_rigs.py --cycle0-only, on the CPU),
#               cal.yaml (config.yaml with a calibration of 4 + 1 x 2 sets) and the
#               calibration's inputs under cal/ (the measured test, its conditions, 3
#               specimens), as `snakemake` builds them.
# Each step has its own time limit, in the order of what matters most; logs go to $OUT.
set -u
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
export PYTHONUNBUFFERED=1 NUMBA_CUDA_LOW_OCCUPANCY_WARNINGS=0
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
    --target /tmp/site .whl/*.whl || exit 1
export PYTHONPATH=/tmp/site:$PWD/src
if ! python3 -c "import numpy; numpy.row_stack" 2>/dev/null; then   # numpy 2.5 dropped it;
    mkdir -p /tmp/shim                                               # some numba use it
    printf 'import numpy\nnumpy.row_stack = numpy.vstack\n' > /tmp/shim/sitecustomize.py
    export PYTHONPATH=/tmp/shim:$PYTHONPATH
fi
nvidia-smi --query-gpu=name,memory.total,driver_version,clocks.sm,clocks.max.sm --format=csv
python3 -c "import sys, numpy, numba; from importlib.metadata import version as v
print('python', sys.version.split()[0], 'numpy', numpy.__version__, 'numba', numba.__version__,
      'numba-cuda', v('numba-cuda'), 'row_stack', hasattr(numpy, 'row_stack'))"
nproc

STEPS=" ${*:-rigs_biaxial calibrate_cuda rigs_box ensemble tests_real_gpu} "
step() {   # step NAME SECONDS COMMAND...: one benchmark, its log under $OUT
    local name=$1 limit=$2; shift 2
    [[ $STEPS == *" $name "* ]] || return 0
    local own="LIMIT_$name"
    limit=${!own:-$limit}
    echo "=== $name (limit $limit s) $(date +%T)"
    local t0=$SECONDS
    timeout "$limit" "$@" > "$OUT/$name.log" 2>&1
    local rc=$?
    pkill -f "python3 bench/gpu_" 2>/dev/null    # a CPU child that timeout left running
    tail -n 25 "$OUT/$name.log"
    echo "=== $name: rc $rc in $((SECONDS - t0)) s"
}

step rigs_biaxial 160 python3 bench/gpu_rigs.py --assembled .devcarry/biaxial_full.nc \
    --resume .devcarry/biaxial_full_c0.npz --batch 100 --cycles 3 --budget 100 --kernels
step calibrate_cuda 140 python3 -m ballaststudy.cli calibrate .devcarry/cal/p60_q230_f5.nc \
    --conditions .devcarry/cal/p60_q230_f5.yaml --specimens .devcarry/cal/case0.nc \
    .devcarry/cal/case1.nc .devcarry/cal/case2.nc --out-dir "$OUT/cal_cuda" --backend cuda \
    --config .devcarry/cal.yaml
if [ -d "$OUT/cal_cuda" ]; then          # (its cases/ folder is too deep to come back)
    (cd "$OUT/cal_cuda" && tar czf "$OUT/cal_cuda.tgz" evaluations.nc summary.md calibrated.yaml)
    rm -rf "$OUT/cal_cuda"
fi
step rigs_box 90 python3 bench/gpu_rigs.py --rig box --config config/thesis.yaml \
    --assembled .devcarry/box_thesis.nc --resume .devcarry/box_thesis_c0.npz --batch 160 \
    --cycles 6 --budget 50 --kernels
step ensemble 70 python3 bench/gpu_ensemble.py --batches 1,100,1000 --steps 500 \
    --cpu-steps 1000 --check-steps 300 --bonded-batches 100
step tests_real_gpu 45 env BALLASTSTUDY_TEST_GPU=real python3 -m pytest tests/dem/gpu -q -n 8 \
    -p no:cacheprovider --tb=line -rfE
