"""Where the calibration's and the loop's cases run: this machine's processes, or the
workers of a Dask scheduler, started on a batch system by dask-jobqueue (spec, pool), and
the guard that stops a case whose checkpoint interval outlives its worker (guard)."""
