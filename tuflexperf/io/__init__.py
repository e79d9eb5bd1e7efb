"""Reading and validating the project's files (YAML, CSV, .mat); analyses never touch disk."""
