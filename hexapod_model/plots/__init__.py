"""The studies' figures as matplotlib ``Figure`` objects saved to PNG (no pyplot, no backend choice)."""
