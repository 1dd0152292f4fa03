"""An example flexsat plug-in: the two-mass-spring benchmark of Wie & Bernstein (1992).

One plant (:mod:`.plant`), one law (:mod:`.law`), one case (:mod:`.case`) and one check
(:mod:`.check`), each declared as an entry point in this package's ``pyproject.toml``;
flexsat's docs/plugins.md walks through them.
"""
