"""Tests of scenarios/ (tests/layout_rules.py)."""
