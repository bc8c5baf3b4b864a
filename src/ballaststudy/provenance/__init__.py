"""Provenance records: what made an output, from which inputs, with which parameters."""

from .record import Recorder, sha256_file

__all__ = ["Recorder", "sha256_file"]
