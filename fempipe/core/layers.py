"""The layers of the package, lowest first: a module imports from its own layer or lower ones.

This module is data (and one lookup function): ``tests/test_layering.py`` reads it without
importing fempipe, parses every module of the package and fails on an import of a higher
layer, on a private name (``_x``) imported from another module, and on a cycle of imports,
even through imports inside functions.

The layers, in rank order (:data:`LAYERS`): ``core`` < ``model`` < ``solvers`` <
``analyses`` (statics < stability < dynamics < limit_cycle < space < parametric < branches:
bifurcation diagrams and periodic orbits) < ``studies`` < ``io`` < ``plotting`` < ``validation`` <
``bench`` < ``cli`` < ``facade`` (``fempipe`` itself, ``python -m fempipe`` and the course's
answer checks ``fempipe.course``; nothing in the package imports it).  The package
``fempipe.analyses`` itself, and an analysis not listed yet, rank with the statics.

What each layer holds: docs/api/usage.md, "The package, layer by layer".
"""

from __future__ import annotations

__all__ = ["FACADE", "LAYERS", "layer_of"]

#: (layer name, module prefixes) in rank order, lowest first.  A module belongs
#: to the layer of its longest matching prefix (the prefix itself or a module
#: below it: ``fempipe.model`` holds ``fempipe.model.operators``).
LAYERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("core", ("fempipe.core",)),
    ("model", ("fempipe.model",)),
    ("solvers", ("fempipe.solvers",)),
    ("analyses.statics", ("fempipe.analyses", "fempipe.analyses.statics")),
    ("analyses.stability", ("fempipe.analyses.stability",)),
    ("analyses.dynamics", ("fempipe.analyses.dynamics",)),
    ("analyses.limit_cycle", ("fempipe.analyses.limit_cycle",)),
    ("analyses.space", ("fempipe.analyses.space",)),
    ("analyses.parametric", ("fempipe.analyses.parametric",)),
    (
        "analyses.branches",
        (
            "fempipe.analyses.bifurcation",
            "fempipe.analyses.periodic",
            "fempipe.analyses.space.diagram",  # the 3-D diagram: a diagram over the 3-D motion
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
    >>> layer_of("fempipe.model.operators")
    (1, 'model')
    >>> layer_of("fempipe")
    (14, 'facade')
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
