"""Tests of fmus/slave/ (tests/layout_rules.py)."""
