"""Rendering: meshcat scenes saved as self-contained static HTML, matplotlib helpers."""
