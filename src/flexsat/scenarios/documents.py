"""Reading a scenario document: the text (a file or a string, UTF-8, bounded in size), the YAML
(bounded nesting and value count, no duplicate keys or recursive aliases), then the schema of its
``kind`` (:func:`load_scenario`)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Any, cast

import yaml
from pydantic import BaseModel

from flexsat import limits
from flexsat.scenarios.errors import Problem, ScenarioError
from flexsat.scenarios.fields import Document
from flexsat.scenarios.kind import DEFAULT_KIND, scenario_kind

DEFAULT_SCENARIO = "tamu_default.yaml"  # package data of flexsat.cases


def _file_of(source: object) -> Path | None:
    """The file a source names: a Path, or a one-line string that ends in ``.yaml``/``.yml`` or
    names an existing file; None for the text itself."""
    if isinstance(source, Path):
        return source
    if not isinstance(source, str) or "\n" in source:
        return None
    try:
        return (
            Path(source) if source.endswith((".yaml", ".yml")) or Path(source).is_file() else None
        )
    except (OSError, ValueError):  # too long or otherwise impossible as a file name: text
        return None


def _read(source: str | bytes | Path) -> str:
    """Scenario text from a file (:func:`_file_of`) or as given (bytes are decoded as UTF-8);
    at most :data:`flexsat.limits.MAX_DOCUMENT_BYTES`."""
    name = "scenario: the document"
    file_name = _file_of(source)
    content: str | bytes
    if file_name is not None:
        name = f"scenario: {str(source)!r}"
        try:
            with open(file_name, "rb") as file:
                content = file.read(limits.MAX_DOCUMENT_BYTES + 1)
        except OSError as exc:
            raise ScenarioError(
                [Problem("", f"cannot read {str(source)!r} ({exc.strerror})")]
            ) from None
    else:
        assert not isinstance(source, Path)  # _file_of names every Path
        content = source
    if isinstance(content, bytes):
        try:
            content = content.decode("utf-8")
        except UnicodeDecodeError as exc:
            if len(content) <= limits.MAX_DOCUMENT_BYTES:
                raise ScenarioError(
                    [
                        f"{name} is not UTF-8 text (byte 0x{content[exc.start]:02x} "
                        f"at offset {exc.start}); save it as UTF-8"
                    ]
                ) from None
    if len(content) > limits.MAX_DOCUMENT_BYTES:
        raise ScenarioError(
            [
                f"{name} is larger than {limits.MAX_DOCUMENT_BYTES:,} bytes "
                "(flexsat.limits.MAX_DOCUMENT_BYTES); a scenario is a few kB"
            ]
        )
    if isinstance(content, bytes):  # not UTF-8, and longer than the limit: refused above
        raise AssertionError("unreachable")
    return content


# PyYAML ships no type information (yaml.* is ignore_missing_imports): SafeLoader is Any
class _Loader(yaml.SafeLoader):  # type: ignore[misc]
    """YAML's safe loader, refusing as it composes nesting deeper than
    :data:`flexsat.limits.MAX_NESTING` (PyYAML recurses once per level) and more than
    :data:`flexsat.limits.MAX_DOCUMENT_NODES` values."""

    def __init__(self, stream: str) -> None:
        super().__init__(stream)
        self._depth = self._nodes = 0

    def compose_node(self, parent: Any, index: Any) -> Any:
        self._depth += 1
        self._nodes += 1
        try:
            line = self.peek_event().start_mark.line + 1
            if self._depth > limits.MAX_NESTING:
                raise ScenarioError(
                    [
                        Problem(
                            "",
                            f"nested deeper than {limits.MAX_NESTING} levels "
                            f"at line {line} (flexsat.limits.MAX_NESTING)",
                        )
                    ]
                )
            if self._nodes > limits.MAX_DOCUMENT_NODES:
                raise ScenarioError(
                    [
                        Problem(
                            "",
                            f"more than {limits.MAX_DOCUMENT_NODES:,} values "
                            f"(at line {line}; flexsat.limits.MAX_DOCUMENT_NODES)",
                        )
                    ]
                )
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1


_MERGE = "tag:yaml.org,2002:merge"


def _check_nodes(
    node: Any, path: str, loader: _Loader, sizes: dict[int, int], open_: set[int]
) -> int:
    """Number of values under ``node`` with aliases expanded; refuses duplicate keys (the last
    would silently win), recursive aliases and more than MAX_DOCUMENT_NODES values."""
    if id(node) in sizes:
        return sizes[id(node)]
    if id(node) in open_:
        raise ScenarioError(
            [Problem(path, "an alias refers to the value that contains it (recursive anchor)")]
        )
    open_.add(id(node))
    size = 1
    if isinstance(node, yaml.MappingNode):
        lines: dict[Any, int] = {}
        for key_node, value_node in node.value:
            key = (
                loader.construct_object(key_node)
                if isinstance(key_node, yaml.ScalarNode) and key_node.tag != _MERGE
                else None
            )
            here = f"{path}.{key}" if path else str(key)
            line = key_node.start_mark.line + 1
            if key is not None and key in lines:
                raise ScenarioError(
                    [
                        Problem(
                            f"{here}",
                            f"duplicate key (lines {lines[key]} and {line}); give it once",
                        )
                    ]
                )
            if key is not None:
                lines[key] = line
            size += _check_nodes(key_node, here, loader, sizes, open_) + _check_nodes(
                value_node, here, loader, sizes, open_
            )
    elif isinstance(node, yaml.SequenceNode):
        size += sum(
            _check_nodes(item, f"{path}[{i}]", loader, sizes, open_)
            for i, item in enumerate(node.value)
        )
    open_.discard(id(node))
    if size > limits.MAX_DOCUMENT_NODES:
        raise ScenarioError(
            [
                Problem(
                    path,
                    f"more than {limits.MAX_DOCUMENT_NODES:,} "
                    "values once aliases are expanded (flexsat.limits."
                    "MAX_DOCUMENT_NODES)",
                )
            ]
        )
    sizes[id(node)] = size
    return size


def parse_document(text: str) -> Any:
    """The YAML document, checked for nesting, duplicate keys and expanded size first."""
    loader = None
    try:
        loader = _Loader(text)  # its reader refuses non-printable characters
        node = loader.get_single_node()
        if node is None:
            return None
        _check_nodes(node, "", loader, {}, set())
        return loader.construct_document(node)
    except yaml.YAMLError as exc:
        raise ScenarioError([Problem("yaml", f"{exc}")]) from None
    finally:
        if loader is not None:
            loader.dispose()


def load_scenario(source: str | bytes | Path) -> BaseModel:
    """Parse and validate a scenario (stage 1: YAML, schema, units, section rules).

    ``kind`` (default ``maneuver``) picks the kind (:func:`flexsat.scenarios.kind.scenario_kinds`,
    built in or a plug-in), whose document model validates the rest: a
    :class:`~flexsat.scenarios.maneuver.Scenario` for a maneuver, a
    :class:`flexsat.scenarios.batch.BatchScenario` for a sweep or a Monte Carlo, ...

    Parameters
    ----------
    source : str, bytes or Path
        A path to a YAML file, or the YAML text itself (bytes: UTF-8).

    Raises
    ------
    ScenarioError
        Listing every problem found, each as ``field.path: rule``.
    """
    text = _read(source)
    data = parse_document(text)
    if not isinstance(data, dict):
        raise ScenarioError(
            [Problem("", "must be a YAML mapping (name, case, simulation, runs, ...)")]
        )
    scenario = scenario_kind(data.get("kind", DEFAULT_KIND)).validate(data)
    # a kind's document has the private attributes of a fields.Document (ScenarioKind.document)
    document = cast(Document, scenario)
    document._source = text
    file_name = _file_of(source)
    if file_name is not None:
        document._folder = file_name.resolve().parent
    return scenario


def default_scenario() -> BaseModel:
    """The embedded default: the TAMU 40 deg slew, Law I against Law II (``flexsat run``)."""
    return load_scenario(resources.files("flexsat.cases").joinpath(DEFAULT_SCENARIO).read_text())


__all__ = ["DEFAULT_SCENARIO", "default_scenario", "load_scenario", "parse_document"]
