"""Tests of kernels/ (tests/layout_rules.py)."""
