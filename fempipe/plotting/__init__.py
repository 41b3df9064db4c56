"""Figures a reader of the paper recognizes.  matplotlib is imported lazily
inside each function; every function takes ``ax=None`` and returns the Axes."""
