"""tuflexperf: from wind-tunnel runs of electric ducted fans to performance verdicts."""

__version__ = "0.1.0"
