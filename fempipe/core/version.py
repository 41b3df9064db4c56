"""The version of fempipe (``fempipe --version``, the validation report's environment).

In the core so that every layer can read it without importing the facade
:mod:`fempipe`, which re-exports it.  ``pyproject.toml`` states the same number.
"""

__version__ = "0.1.0"
