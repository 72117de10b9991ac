"""File formats: CSV tables of leg readings and poses."""
