"""The discrepancy loop: a log's nominal model, the candidate effects, the named causes, the
extended model and its gain (inverse and forward views)."""
