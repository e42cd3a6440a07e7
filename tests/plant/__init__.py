"""Tests of plant/ (tests/layout_rules.py)."""
