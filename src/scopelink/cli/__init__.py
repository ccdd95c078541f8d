"""The scopelink command line."""
