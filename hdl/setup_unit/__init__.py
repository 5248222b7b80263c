"""Triangle setup (seeds 001, 002): sort, Omega and its reciprocal, coefficients, edge DDAs."""
from .setup import Setup, Widths

__all__ = ["Setup", "Widths"]
