"""Tests of fmus/cosim/ (tests/layout_rules.py)."""
