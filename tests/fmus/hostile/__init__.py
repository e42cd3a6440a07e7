"""Tests of fmus/hostile/ (tests/layout_rules.py)."""
