"""Impact Explorer: the Panel web app on top of impactlib (served file: app/app.py)."""
