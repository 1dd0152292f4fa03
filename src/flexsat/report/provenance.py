"""Where a report comes from: the flexsat version, the scenario's fingerprint, the command and
the date, on one line of the page.

Two runs of the same scenario with the same flexsat write the same report files but for that one
line, ``<p class="provenance">...</p>``: the date it was written and the command that wrote it
differ from run to run (:func:`without_provenance` takes it out, to compare two pages). Where
the environment variable ``SOURCE_DATE_EPOCH`` is set (seconds since 1970, the convention of
reproducible builds), it is the date written, and identical runs of the same command write
identical files.
"""

from __future__ import annotations

import hashlib
import html
import os
import re
from dataclasses import dataclass
from datetime import UTC, datetime

from flexsat.input_checks import FieldError

#: the provenance line of a page (one line, :func:`provenance_html`)
PROVENANCE_LINE = re.compile(r'^<p class="provenance">.*</p>\n', re.MULTILINE)


@dataclass(frozen=True)
class Provenance:
    """The origin of a report.

    Attributes
    ----------
    version : str
        flexsat's version.
    written : str
        When, UTC, ISO 8601 to the second.
    scenario_sha256 : str
        SHA-256 of the scenario file's text (UTF-8), hexadecimal.
    command : str
        The command line that wrote it, or how it was written (the Python API).
    """

    version: str
    written: str
    scenario_sha256: str
    command: str


def report_date() -> datetime:
    """Now (UTC), or ``SOURCE_DATE_EPOCH`` where it is set.

    Raises
    ------
    FieldError
        Naming ``SOURCE_DATE_EPOCH`` when it is not a whole number of seconds.
    """
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    if epoch is None:
        return datetime.now(UTC)
    try:
        return datetime.fromtimestamp(int(epoch), UTC)
    except (ValueError, OverflowError, OSError):
        raise FieldError(
            "SOURCE_DATE_EPOCH", f"must be a whole number of seconds since 1970, got {epoch!r}"
        ) from None


def provenance(scenario_text: str, command: str | None = None) -> Provenance:
    """The provenance of a report of the scenario whose file reads ``scenario_text``, written
    now by ``command`` (None: through the Python API)."""
    from flexsat import __version__

    return Provenance(
        version=__version__,
        written=report_date().strftime("%Y-%m-%dT%H:%M:%SZ"),
        scenario_sha256=hashlib.sha256(scenario_text.encode("utf-8")).hexdigest(),
        command=command if command is not None else "flexsat.report.write_report (Python API)",
    )


def provenance_html(origin: Provenance) -> str:
    """The page's provenance line (module docstring), ending with a newline."""
    esc = html.escape
    return (
        f'<p class="provenance">flexsat {esc(origin.version)} · written {esc(origin.written)} · '
        f"scenario SHA-256 <code>{esc(origin.scenario_sha256)}</code> · command "
        f"<code>{esc(origin.command)}</code></p>\n"
    )


def without_provenance(page: str) -> str:
    """``page`` without its provenance line: what two identical runs write alike."""
    return PROVENANCE_LINE.sub("", page)


__all__ = [
    "PROVENANCE_LINE",
    "Provenance",
    "provenance",
    "provenance_html",
    "report_date",
    "without_provenance",
]
