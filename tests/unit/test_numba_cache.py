"""Stale Numba caches of the kernels are dropped when any kernel source changes."""

from __future__ import annotations

import shutil

import fibersweep.numba_cache as nc


def test_a_changed_source_clears_the_cache_once(tmp_path, monkeypatch):
    root = tmp_path / "pkg"
    for pkg in ("fiber", "flow"):
        (root / pkg / "__pycache__").mkdir(parents=True)
        (root / pkg / "k.py").write_text("x = 1\n")
        (root / pkg / "__pycache__" / "k.f-1.py311.nbi").write_bytes(b"index")
        (root / pkg / "__pycache__" / "k.f-1.py311.1.nbc").write_bytes(b"code")
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)

    def sync():
        monkeypatch.setattr(nc, "_done", False)  # as in a new process
        return nc.sync_kernel_cache(root)

    assert sync()  # no stamp yet: caches of unknown sources go
    assert not list(root.rglob("*.nb[ic]"))
    shutil.copy(__file__, root / "flow" / "__pycache__" / "k.f-1.py311.nbi")  # recompiled
    assert not sync()  # same sources: the cache is kept
    assert (root / "flow" / "__pycache__" / "k.f-1.py311.nbi").exists()
    (root / "fiber" / "k.py").write_text("x = 2\n")  # an effect module edited
    assert sync() and not list(root.rglob("*.nb[ic]"))
