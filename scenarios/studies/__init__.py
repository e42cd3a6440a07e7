"""Studies: each writes under out/; docs change only through an explicit --docs."""
