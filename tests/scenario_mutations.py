"""Mutations of scenario documents for the property tests (tests/scenarios/test_*properties.py):
values of the wrong type, extreme and non-finite numbers, bad units, deep nesting, and the
helpers that replace, delete or reach a value at a key path of a parsed document."""

from __future__ import annotations

import math
import time

from hypothesis import strategies as st

NUMBERS = st.sampled_from(
    [0, -1, 1e308, -1e308, 1e-308, 2**70, -(2**70), 1e29, 1.5, 1e12, math.nan, math.inf, -math.inf]
)
BAD_UNITS = st.sampled_from(
    [
        "1 kg",
        "15 deg",
        "100 percent",
        "nan s",
        "inf Hz",
        "1e400 s",
        "1e12 s",
        "-3 N*m",
        "5 furlong",
        "ozf*in",
        "",
        "  ",
        "1 1 s",
    ]
)
WRONG_TYPES = st.one_of(
    st.none(),
    st.booleans(),
    st.lists(st.integers(), max_size=3),
    st.dictionaries(st.sampled_from(["a", "angle", "g1"]), st.integers(), max_size=2),
    st.text(max_size=20),
)


def nested(depth: int):
    """A value nested ``depth`` levels deep, mappings and lists alternating."""
    value = 1
    for level in range(depth):
        value = [value] if level % 2 else {"k": value}
    return value


VALUES = st.one_of(NUMBERS, BAD_UNITS, WRONG_TYPES, st.integers(20, 60).map(nested))


def key_paths(node, prefix=()) -> list[tuple]:
    """Every key path of a document (mappings and list items)."""
    items = (
        node.items()
        if isinstance(node, dict)
        else enumerate(node)
        if isinstance(node, list)
        else ()
    )
    out = []
    for key, value in items:
        out.append(prefix + (key,))
        out.extend(key_paths(value, prefix + (key,)))
    return out


def get_at(data, path):
    """The value at key path ``path``."""
    for key in path:
        data = data[key]
    return data


def set_at(data, path, value):
    """Replace the value at key path ``path``."""
    get_at(data, path[:-1])[path[-1]] = value


def delete_at(data, path):
    """Delete the key (or list item) at key path ``path``."""
    del get_at(data, path[:-1])[path[-1]]


def mutate(draw, data, values, unknown_keys, path_first: bool = False):
    """One to three mutations of the parsed document ``data``, in place: a value at a key path
    replaced by one of ``values``, a key deleted, or an unknown key (one of ``unknown_keys``)
    added to a mapping. ``draw`` is a ``@st.composite``'s; ``path_first`` draws the key path
    before the action (the order a test's stored examples were made with)."""
    for _ in range(draw(st.integers(1, 3))):
        paths = key_paths(data)
        if path_first:
            path = draw(st.sampled_from(paths)) if paths else ()
        action = draw(st.sampled_from(["set", "set", "set", "delete", "unknown"]))
        if not path_first:
            path = draw(st.sampled_from(paths)) if paths else ()
        if action == "set" and path:
            set_at(data, path, draw(values))
        elif action == "delete" and path:
            delete_at(data, path)
        else:
            parents = [()] + [p for p in paths if isinstance(get_at(data, p), dict)]
            get_at(data, draw(st.sampled_from(parents)))[draw(st.sampled_from(unknown_keys))] = 1
    return data


#: a property test's wall-time allowance over its CPU bound: enough for a machine loaded
#: several times over its cores, short of a hang (a run waiting on a lock uses no CPU)
HANG_FACTOR = 6.0


class Clock:
    """Started at construction; :meth:`check` bounds the work done since (process CPU time,
    which the machine's load does not inflate) and, ``HANG_FACTOR`` times looser, the wall
    time (which catches a hang that burns no CPU)."""

    def __init__(self) -> None:
        self.cpu, self.wall = time.process_time(), time.perf_counter()

    def check(self, bound: float) -> None:
        cpu, wall = time.process_time() - self.cpu, time.perf_counter() - self.wall
        assert cpu < bound, f"{cpu:.1f} s of CPU (bound {bound} s)"
        assert wall < HANG_FACTOR * bound, f"{wall:.1f} s wall (bound {HANG_FACTOR * bound} s)"
