"""What a finished drape is worth: coverage, the law's limits, wrinkling (``docs/results.md``)."""
