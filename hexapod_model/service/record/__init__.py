"""The record a fixture's cycle publishes for each reading set, and its pose values."""
