"""A small sample of benchmarks/fuzz_cli.py, in process: every input class of issue 32
(extreme values, wrong structures, FIFOs and devices, options only the edge may refuse,
valid designs, tiny sweeps) ends in an answer or one clean refusal, with no valid design
refused, no null without a reason and no partial file."""

from __future__ import annotations

import random
import warnings


def test_a_sample_of_every_input_class_is_answered_or_refused_cleanly(fuzz, tmp_path):
    keys = fuzz.preset_keys()
    seen: dict[str, int] = {}
    bad = []
    k = 0
    while min((seen.get(c, 0) for c in fuzz.CLASSES), default=0) < 4 and k < 400:
        rng = random.Random(f"sample-{k}")
        kind, argv = fuzz.make_any(rng, keys, tmp_path, k)
        k += 1
        if kind == "extremes" and argv[0] == "scale":  # seconds each: the full run has them
            continue
        if seen.get(kind, 0) >= 6:
            continue
        seen[kind] = seen.get(kind, 0) + 1
        with warnings.catch_warnings():
            warnings.simplefilter("default")
            cls, detail = fuzz.run_input(kind, argv, 60.0, tmp_path)
        if cls != "ok":
            bad.append((kind, cls, detail, argv))
    assert set(seen) == set(fuzz.CLASSES)
    assert not bad, bad


def test_the_null_check_finds_an_unexplained_null_and_accepts_a_noted_one(fuzz):
    assert fuzz.nulls_unexplained({"a": {"x": None}}) == ["a/x"]
    assert fuzz.nulls_unexplained({"a": {"x": None, "note": "why"}}) == []
    assert fuzz.nulls_unexplained({"a": {"x": [1, None]}, "nulls": {"a/x": "empty"}}) == []
