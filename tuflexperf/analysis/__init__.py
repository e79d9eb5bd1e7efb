"""Performance analyses, each a CasADi problem built once per case and reused."""
