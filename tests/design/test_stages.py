"""The stage engine of design studies: fingerprints name exactly what went into a stage, and the
cache publishes an entry whole or not at all."""

from __future__ import annotations

import hashlib
import json

import numpy as np
import pytest

import flexsat.design.stages as stages
from flexsat.design.stages import (
    Stage,
    StageCache,
    canonical_json,
    file_digest,
    fingerprint,
    read_arrays,
    write_arrays,
)


def test_fingerprint_is_the_sha256_of_the_canonical_payload():
    section = {"b": [1, 2.5], "a": "x"}
    payload = {"stage": "s", "section": section, "upstream": ["u"], "flexsat": stages.__version__}
    text = json.dumps(payload, sort_keys=True, separators=(",", ":"), ensure_ascii=False)
    assert fingerprint("s", section, ["u"]) == hashlib.sha256(text.encode()).hexdigest()


def test_fingerprint_ignores_key_order_and_follows_every_input(monkeypatch):
    base = fingerprint("law", {"a": 1, "b": {"c": 2.0, "d": [1, 2]}}, ["m"])
    assert fingerprint("law", {"b": {"d": [1, 2], "c": 2.0}, "a": 1}, ["m"]) == base
    changed = [
        fingerprint("law", {"a": 1, "b": {"c": 2.0000001, "d": [1, 2]}}, ["m"]),
        fingerprint("law", {"a": 1, "b": {"c": 2.0, "d": [2, 1]}}, ["m"]),
        fingerprint("law", {"a": 1, "b": {"c": 2.0, "d": [1, 2]}}, ["n"]),
        fingerprint("run", {"a": 1, "b": {"c": 2.0, "d": [1, 2]}}, ["m"]),
    ]
    monkeypatch.setattr(stages, "__version__", "999")
    changed.append(fingerprint("law", {"a": 1, "b": {"c": 2.0, "d": [1, 2]}}, ["m"]))
    assert len({base, *changed}) == 6


def test_canonical_json_refuses_nan():
    with pytest.raises(ValueError):
        canonical_json({"a": float("nan")})


def test_stage_of_chains_the_upstream_keys():
    model = Stage.of("model", "model", {"n": 1})
    modes = Stage.of("modes", "modes", {"k": 2}, [model])
    assert modes.key == fingerprint("modes", {"k": 2}, [model.key])
    other = Stage.of("modes", "modes", {"k": 2}, [Stage.of("model", "model", {"n": 2})])
    assert other.key != modes.key


def test_file_digest_reads_the_bytes(tmp_path):
    path = tmp_path / "f.bin"
    path.write_bytes(b"abc" * 1000)
    assert file_digest(path) == hashlib.sha256(b"abc" * 1000).hexdigest()


def test_arrays_round_trip_bit_for_bit(tmp_path):
    rng = np.random.default_rng(1)
    arrays = {
        "K": rng.standard_normal((3, 7)),
        "poles": rng.standard_normal(5) + 1j * rng.standard_normal(5),
        "scalar": np.float64(np.pi),
    }
    write_arrays(tmp_path, arrays, {"a": [1, "b"]})
    back, info = read_arrays(tmp_path)
    assert info == {"a": [1, "b"]}
    assert set(back) == set(arrays)
    for name, value in arrays.items():
        assert np.array_equal(back[name], value)
        assert np.iscomplexobj(back[name]) == np.iscomplexobj(value)


def _json_stage(cache: StageCache, stage: Stage, compute):
    return cache.get(
        stage,
        compute,
        lambda value, folder: (folder / "v.json").write_text(json.dumps(value)),
        lambda folder: json.loads((folder / "v.json").read_text()),
        lambda value: {"value": value},
    )


def test_a_second_get_reads_the_cache(tmp_path):
    cache, stage = StageCache(tmp_path), Stage.of("s", "s", {"x": 1})
    calls = []
    value, record = _json_stage(cache, stage, lambda: calls.append(1) or [1, 2])
    assert (value, record.cached, calls) == ([1, 2], False, [1])
    value, record = _json_stage(cache, stage, lambda: calls.append(1) or [1, 2])
    assert (value, record.cached, calls) == ([1, 2], True, [1])
    assert record.summary == {"value": [1, 2]}


def test_a_failed_write_publishes_nothing(tmp_path):
    cache, stage = StageCache(tmp_path), Stage.of("s", "s", {"x": 1})

    def half_written(folder):
        (folder / "part.json").write_text("{")
        raise OSError("disk full")

    with pytest.raises(OSError, match="disk full"):
        cache.write(stage, half_written)
    assert list(tmp_path.iterdir()) == []  # neither the entry nor its temporary folder


def test_an_unreadable_entry_is_computed_afresh(tmp_path):
    cache, stage = StageCache(tmp_path), Stage.of("s", "s", {"x": 1})
    _json_stage(cache, stage, lambda: [1])
    (cache.entry(stage) / "v.json").write_text("{not json")
    value, record = _json_stage(cache, stage, lambda: [2])
    assert (value, record.cached) == ([2], False)
    assert json.loads((cache.entry(stage) / "v.json").read_text()) == [2]


def test_an_entry_already_published_is_kept(tmp_path):
    # two processes computing one stage: the first rename wins, the second's copy is dropped
    cache, stage = StageCache(tmp_path), Stage.of("s", "s", {"x": 1})
    cache.write(stage, lambda folder: (folder / "v.json").write_text("1"))
    cache.write(stage, lambda folder: (folder / "v.json").write_text("2"))
    assert (cache.entry(stage) / "v.json").read_text() == "1"
    assert [p.name for p in tmp_path.iterdir()] == [cache.entry(stage).name]


def test_a_stage_being_computed_elsewhere_is_waited_for_and_read(tmp_path):
    # two processes of a batch (here two threads, each with its own open file: flock locks
    # belong to the open file) ask for one stage: the second waits for the first's entry and
    # reads it rather than computing it again
    import threading

    cache, stage = StageCache(tmp_path), Stage.of("s", "s", {"x": 1})
    started, release = threading.Event(), threading.Event()
    computed = []

    def slow():
        started.set()
        release.wait(10)
        computed.append("first")
        return [1]

    first = threading.Thread(target=lambda: _json_stage(cache, stage, slow))
    first.start()
    started.wait(10)
    outcome = []
    second = threading.Thread(
        target=lambda: outcome.append(
            _json_stage(cache, stage, lambda: computed.append("second") or [2])
        )
    )
    second.start()
    second.join(0.3)
    assert second.is_alive()  # waiting on the lock, not computing
    release.set()
    first.join(10)
    second.join(10)
    value, record = outcome[0]
    assert computed == ["first"] and value == [1] and record.cached


def test_the_record_of_a_cached_stage_is_read_without_its_result(tmp_path):
    cache, stage = StageCache(tmp_path), Stage.of("s", "s", {"x": 1})
    assert cache.recorded(stage) is None
    _json_stage(cache, stage, lambda: [3, 4])
    (cache.entry(stage) / "v.json").unlink()  # the result is not what recorded() reads
    record = cache.recorded(stage)
    assert record is not None and record.cached and record.summary == {"value": [3, 4]}
