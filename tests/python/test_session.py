"""hybridtree.Session: meshing an edited tree reuses the unchanged jobs and gives Tree.mesh's bytes."""
import numpy as np
import pytest

import hybridtree


def two_segments(radius):
    b = hybridtree.Builder()
    left = b.segment((-1, 0, 0), (0, 0, 0), radius=0.5)
    right = b.segment((0.6, 0, 0), (1.6, 0, 0), radius=radius)
    b.set_name(right, "right")
    return b.build(b.unite([left, right]))


def test_an_edit_reuses_the_unchanged_subtree_and_matches_from_scratch():
    session = hybridtree.Session(64 << 20)
    _, _, first = session.mesh(two_segments(0.5), precision=0.05)
    assert first["cache"]["hits"] == 0
    assert first["cache"]["misses"] > 0
    edited = two_segments(0.55)
    v, t, stats = session.mesh(edited, precision=0.05)
    assert stats["cache"]["hits"] >= 1
    assert "right" not in stats["cache"]["reused_nodes"]
    v0, t0, _ = edited.mesh(precision=0.05)
    assert v.tobytes() == v0.tobytes()
    assert np.array_equal(t, t0)
    assert session.cache_entries > 0 and session.cache_bytes > 0
    session.clear()
    assert session.cache_entries == 0


def test_a_folder_shares_results_across_sessions(tmp_path):
    folder = tmp_path / "cache"
    first = hybridtree.Session(64 << 20, folder=str(folder))
    v0, t0, _ = first.mesh(two_segments(0.5), precision=0.05)
    del first
    second = hybridtree.Session(64 << 20, folder=folder, folder_bytes=64 << 20)  # a pathlib.Path
    v, t, stats = second.mesh(two_segments(0.5), precision=0.05)
    assert stats["cache"]["misses"] == 0
    assert stats["cache"]["disk"]["hits"] == stats["cache"]["hits"] > 0
    assert v.tobytes() == v0.tobytes() and np.array_equal(t, t0)
    (tmp_path / "a_file").write_text("x")
    with pytest.raises(hybridtree.InputError):
        hybridtree.Session(folder=str(tmp_path / "a_file"))
