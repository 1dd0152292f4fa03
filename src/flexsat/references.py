"""The published sources behind the cases and checks, cited so that a reader can find them.

The cases and checks name their sources by a short citation (authors and year, :data:`SEEDS`)
and a locator a reader holding the source can use (section, table, figure, equation, attachment).
:func:`references` lists the full citations (authors, title, report or journal, year) of the
sources a text names, with the attached papers of the Texas A&M report it names. A source still
written as a transcript file name (``seed NNN_<hash>.txt``, the form plug-ins written against
older versions may use) is understood too, and :func:`cite` turns it into the short citation.

Deliberately free of numpy and the models: ``flexsat cases`` and ``flexsat validate`` print
through it before anything heavy loads.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass


@dataclass(frozen=True)
class Reference:
    """A published source: ``short`` (authors and year, used in tables) and ``full``."""

    short: str
    full: str


#: the five seed transcripts, by number
SEEDS: dict[str, Reference] = {
    "000": Reference(
        "Junkins, Pollock & Rahman 1990",
        'J. L. Junkins, T. C. Pollock and Z. H. Rahman, "Analytical and Experimental Research '
        'on Large Angle Maneuvers of Flexible Structures", final report, AFOSR contract '
        "F49620-87-C-0078, Texas A&M University, May 1990 (DTIC AD-A226 679; 14 attached papers)",
    ),
    "001": Reference(
        "Hailey, Sortun & Agrawal c. 1992",
        'J. A. Hailey, C. D. Sortun and B. N. Agrawal, "Experimental Verification of Attitude '
        'Control Techniques for Slew Maneuvers of Flexible Spacecraft", conference paper, Naval '
        "Postgraduate School, Monterey (c. 1992; it cites work of October 1991)",
    ),
    "002": Reference(
        "Bainum & Reddy 1979",
        'P. M. Bainum and A. S. S. R. Reddy, "The Dynamics and Control of Large Flexible Space '
        'Structures - II, Part A: Shape and Orientation Control Using Point Actuators", final '
        "report, NASA CR-158684, Howard University, June 1979",
    ),
    "003": Reference(
        "EPS slew study c. 1989",
        "Earth Pointing Satellite slew and integrated structures/control design study for NASA "
        "Langley (report section, title page lost; slew method of Chun, Turner & Juang 1987 "
        "and Chun & Turner 1988), c. 1989",
    ),
    "004": Reference(
        "Agrawal & Bang 1996",
        'B. N. Agrawal and H. Bang, "Adaptive Structures for Large Precision Antennas", '
        "Acta Astronautica, 1996 (IAF-94.1.4.202, 45th IAC, Jerusalem, 1994)",
    ),
}

#: the papers attached to the Texas A&M report (Junkins, Pollock & Rahman 1990)
#: that the cases and checks cite
ATTACHMENTS: dict[int, str] = {
    1: 'J. L. Junkins, Z. H. Rahman and H. Bang, "Near-Minimum-Time Maneuvers of Flexible '
    'Vehicles: A Liapunov Control Law Design Method", AIAA paper 90-1222, 1990',
    2: 'J. L. Junkins, Z. H. Rahman and H. Bang, "Stable Maneuver Control Laws for '
    'Distributed Parameter Systems", Int. Conf. Dynamics of Flexible Structures in Space, '
    "Cranfield, 1990",
    3: 'J. L. Junkins, Z. H. Rahman and H. Bang, "Near-Minimum-Time Maneuvers of Flexible '
    'Vehicles: Analytical and Experimental Results", AIAA Aerospace Sciences Meeting, 1990',
    4: 'Y. Kim and J. L. Junkins, "A Measure of Controllability for Actuator Placement", '
    "AIAA Guidance, Navigation and Control Conference, 1990",
    5: 'J. L. Junkins and Y. Kim, "First and Second Order Sensitivity of the Singular Value '
    'Decomposition", Journal of the Astronautical Sciences 38(1), 1990',
    6: 'G. H. James and J. L. Junkins, "Novel Sensing and Structural Identification Methods: '
    'Preliminary Analytical and Experimental Results", AAS paper 89-425, 1989',
    7: 'N. G. Creamer and J. L. Junkins, "Identification Method for Lightly Damped '
    'Structures", Journal of Guidance, Control, and Dynamics 11(6), 1988',
    8: 'J. L. Junkins and G. H. James, "A Stereo-Triangulation Approach to Sensing for '
    'Structural Identification", AAS paper 88-015, 1988',
    12: 'S. R. Vadali and E.-S. Kim, "Feedback Control of Tethered Satellites Using Liapunov '
    'Stability Theory", AIAA paper 90-1197, 1990',
}

_SEED = re.compile(r"seed (?:file )?(\d{3})_[0-9a-f]{16}\.txt")
_ATTACHMENT = re.compile(r"Att\. (\d+)")


def cite(text: str) -> str:
    """``text`` with every transcript file name (``seed NNN_<16 hex digits>.txt``) replaced by
    its short citation (``seed 000_<hex>.txt`` becomes ``"Junkins, Pollock & Rahman 1990"``).
    Unknown seed numbers are left as they are."""
    return _SEED.sub(lambda m: SEEDS[m.group(1)].short if m.group(1) in SEEDS else m.group(0), text)


def _sources_named(text: str) -> set[str]:
    """The seed numbers whose short citation or transcript file name ``text`` contains."""
    by_name = {m.group(1) for m in _SEED.finditer(text)} & set(SEEDS)
    return by_name | {number for number, ref in SEEDS.items() if ref.short in text}


def references(texts: Iterable[str]) -> list[str]:
    """The full citations of the sources named in ``texts`` (in seed order), each followed by the
    attached papers of the Texas A&M report the same texts name (``Att. N``)."""
    named = [(t, _sources_named(t)) for t in texts]
    seeds = sorted(set().union(*(numbers for _, numbers in named)))
    attachments = sorted(
        {int(n) for t, numbers in named if "000" in numbers for n in _ATTACHMENT.findall(t)}
        & set(ATTACHMENTS)
    )
    lines = []
    for number in seeds:
        ref = SEEDS[number]
        lines.append(f"{ref.short}: {ref.full}")
        if number == "000":
            lines.extend(f"  Att. {n}: {ATTACHMENTS[n]}" for n in attachments)
    return lines


__all__ = ["ATTACHMENTS", "SEEDS", "Reference", "cite", "references"]
