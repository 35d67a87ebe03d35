"""Technologies: process description, built-ins, loading and validation."""
from .technology import Technology, builtin_names, load_technology

__all__ = ["Technology", "builtin_names", "load_technology"]
