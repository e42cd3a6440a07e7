"""Tests of fmus/slaves/ (tests/layout_rules.py)."""
