"""Views: plots, 3D pictures, the browser viewer, progress - they draw what they are given."""
