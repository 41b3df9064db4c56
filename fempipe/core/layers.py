"""The layers of the package, lowest first: a module imports from its own layer or lower ones.

Data and one lookup: ``tests/test_layering.py`` reads it without importing fempipe and fails
on an import of a higher layer, a private name imported from another module, or an import
cycle.  The order is :data:`LAYERS` (``core`` < ``model`` < ``solvers`` < ``analyses`` <
... < ``cli`` < ``facade``); the package ``fempipe.analyses`` and an unlisted analysis rank
with the statics.

What each layer holds: docs/api/usage.md, "The package, layer by layer".
"""

from __future__ import annotations

__all__ = ["FACADE", "LAYERS", "layer_of"]

#: (layer name, module prefixes) in rank order, lowest first.  A module belongs
#: to the layer of its longest matching prefix (the prefix itself or a module
#: below it: ``fempipe.model`` holds ``fempipe.model.plane.operators``).
LAYERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("core", ("fempipe.core",)),
    ("model", ("fempipe.model",)),
    ("solvers", ("fempipe.solvers",)),
    ("analyses.statics", ("fempipe.analyses", "fempipe.analyses.statics")),
    ("analyses.stability", ("fempipe.analyses.stability",)),
    ("analyses.dynamics", ("fempipe.analyses.dynamics",)),
    ("analyses.limit_cycle", ("fempipe.analyses.limit_cycle",)),
    ("analyses.three_d", ("fempipe.analyses.three_d",)),
    ("analyses.parametric", ("fempipe.analyses.parametric",)),
    (
        "analyses.branches",
        (
            "fempipe.analyses.bifurcation",
            "fempipe.analyses.periodic",
            "fempipe.analyses.three_d.diagram",  # the 3-D diagram: a diagram over the 3-D motion
        ),
    ),
    ("studies", ("fempipe.studies",)),
    ("io", ("fempipe.io",)),
    ("plotting", ("fempipe.plotting",)),
    ("validation", ("fempipe.validation",)),
    ("bench", ("fempipe.bench",)),
    ("cli", ("fempipe.cli",)),
    ("facade", ()),
)

#: The modules of the facade, matched exactly (every module starts with ``fempipe``).
FACADE: tuple[str, ...] = ("fempipe", "fempipe.__main__", "fempipe.course")


def layer_of(module: str) -> tuple[int, str] | None:
    """The (rank, name) of the layer of ``module`` (a dotted name), or None if it has none.

    Examples
    --------
    >>> layer_of("fempipe.model.plane.operators")
    (1, 'model')
    >>> layer_of("fempipe")
    (16, 'facade')
    """
    if module in FACADE:
        return len(LAYERS) - 1, LAYERS[-1][0]
    best: tuple[int, int, str] | None = None  # (prefix length, rank, name)
    for rank, (name, prefixes) in enumerate(LAYERS):
        for prefix in prefixes:
            if module == prefix or module.startswith(prefix + "."):
                if best is None or len(prefix) > best[0]:
                    best = (len(prefix), rank, name)
    return None if best is None else (best[1], best[2])
