"""Tests of fmus/export/ (tests/layout_rules.py)."""
