"""The tests, in folders by the product layer they test (tests/layout_rules.py)."""
