"""Tests of repo/ (tests/layout_rules.py)."""
