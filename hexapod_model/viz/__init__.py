"""3-D views: the meshcat scene, static HTML and PNG snapshots, the robot cell (optional ``meshcat``, Chromium)."""
