"""Moved to :mod:`orbatt.dataset.aem`; this name stays for ``from orbatt.aem import ...``."""
from .dataset.aem import Aem, AemSegment, aem_direction_cosine_matrix, read_aem, write_aem  # noqa: F401

__all__ = ["write_aem", "read_aem", "Aem", "AemSegment", "aem_direction_cosine_matrix"]
