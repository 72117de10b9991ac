"""The papers' studies (accuracy, workspace evaluation, tracking, timing): functions that return results."""
