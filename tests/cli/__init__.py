"""Tests of cli/ (tests/layout_rules.py)."""
