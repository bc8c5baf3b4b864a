"""numba's cache under a folder of the engine's sources: an edited source is a new folder
(a kernel inlined from another module is never read stale), nothing another version may be
reading is deleted, and folders of versions unused for STALE_DAYS are removed."""
import os
import time

from numba.core import config

from ballaststudy.dem import _cache


def test_a_changed_source_is_a_new_folder_and_old_ones_age_out(tmp_path, monkeypatch):
    sources, base = tmp_path / "dem", tmp_path / "cache"
    sources.mkdir()
    (sources / "contacts.py").write_text("K = 1\n")
    monkeypatch.setattr(_cache, "HERE", str(sources))
    monkeypatch.setattr(config, "CACHE_DIR", str(base))      # as NUMBA_CACHE_DIR sets it
    _cache.refresh()
    first = config.CACHE_DIR
    assert os.path.isdir(first) and os.path.dirname(first) == str(base / "numba-by-source")
    open(os.path.join(first, "run_steps.nbi"), "w").close()

    (sources / "contacts.py").write_text("K = 2\n")          # a kernel edited
    monkeypatch.setattr(config, "CACHE_DIR", str(base))
    _cache.refresh()
    second = config.CACHE_DIR
    assert second != first and os.path.isfile(os.path.join(first, "run_steps.nbi"))   # kept: in use

    old = time.time() - (_cache.STALE_DAYS + 1) * 86400
    os.utime(first, (old, old))
    monkeypatch.setattr(config, "CACHE_DIR", str(base))
    _cache.refresh()
    assert config.CACHE_DIR == second and not os.path.exists(first) and os.path.isdir(second)


def test_without_numba_cache_dir_it_lives_beside_the_sources(tmp_path, monkeypatch):
    (tmp_path / "a.py").write_text("")
    monkeypatch.setattr(_cache, "HERE", str(tmp_path))
    monkeypatch.setattr(config, "CACHE_DIR", "")
    _cache.refresh()
    assert config.CACHE_DIR.startswith(str(tmp_path / "__pycache__" / "numba-by-source"))
