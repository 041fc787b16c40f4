"""wheelterrain: an open wheel-terrain model for grousered rover wheels on loose soil."""

__version__ = "0.1.0"
