"""Integrators: every method, ours and scipy's, behind one interface (see :mod:`.base`)."""

from .base import METHODS, IntegrationError, Method, get_method, methods_for

__all__ = ["METHODS", "IntegrationError", "Method", "get_method", "methods_for"]
