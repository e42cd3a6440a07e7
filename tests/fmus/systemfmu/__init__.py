"""Tests of fmus/systemfmu/ (tests/layout_rules.py)."""
