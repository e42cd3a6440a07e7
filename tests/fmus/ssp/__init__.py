"""Tests of fmus/ssp/ (tests/layout_rules.py)."""
