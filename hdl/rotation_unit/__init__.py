"""Angular vector rotation (seed 003 §3.1, Fig 7)."""
from .rotation import Rotation

__all__ = ["Rotation"]
