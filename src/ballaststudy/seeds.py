"""Seeds of the jobs: one formula, from the study seed and a job's key."""
import zlib


def job_seed(study_seed, key):
    """The one seed formula: a job's seed from the study seed and the job's key (e.g.
    "G_1-1", "G_1-1/bpm", "G_1-1/case3") via CRC-32 (Python's hash() is salted per process
    and so not reproducible)."""
    return (int(study_seed) * 1_000_003 + zlib.crc32(key.encode())) % 2**63
