"""Tests of fmus/ (tests/layout_rules.py)."""
