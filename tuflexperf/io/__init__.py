"""Reading and validating the project's files (YAML, CSV, .mat): the only place that touches disk."""
