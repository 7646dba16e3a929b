"""Integrators: every method, ours and scipy's, behind one interface (see :mod:`.base`)."""

from .. import _jit  # noqa: F401  (numba's cache folder, set before anything imports numba)
from .base import METHODS, IntegrationError, Method, get_method, methods_for

__all__ = ["METHODS", "IntegrationError", "Method", "get_method", "methods_for"]
