"""Tests of fmus/native/ (tests/layout_rules.py)."""
