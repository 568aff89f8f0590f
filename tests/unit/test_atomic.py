"""One atomic writer: the umask's permissions, no leftovers, the old file kept on failure."""

from __future__ import annotations

import os
import stat

import pytest

from fibersweep.atomic import TMP_GLOB, atomic_path, atomic_write, file_mode


@pytest.mark.parametrize("umask", [0o022, 0o077, 0o002])
def test_new_files_get_the_umask_permissions(tmp_path, umask):
    old = os.umask(umask)
    try:
        assert file_mode() == 0o666 & ~umask
        p = atomic_write(tmp_path / "sub" / "a.json", "{}")
        # mkstemp would give 0600 whatever the umask; plain open gives 0666 & ~umask
        assert stat.S_IMODE(p.stat().st_mode) == 0o666 & ~umask
        with open(tmp_path / "plain", "w"):
            pass
        assert stat.S_IMODE((tmp_path / "plain").stat().st_mode) == 0o666 & ~umask
    finally:
        os.umask(old)


def test_a_failed_write_keeps_the_old_file_and_leaves_nothing(tmp_path):
    p = atomic_write(tmp_path / "t.txt", "old")
    with pytest.raises(RuntimeError), atomic_path(p) as tmp:
        tmp.write_text("half")
        raise RuntimeError("killed mid-write")
    assert p.read_text() == "old"
    assert not list(tmp_path.glob(TMP_GLOB))
    assert atomic_write(p, b"new").read_bytes() == b"new"
    assert not list(tmp_path.glob(TMP_GLOB))
