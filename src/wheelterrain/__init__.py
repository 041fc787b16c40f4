"""wheelterrain: an open wheel-terrain interaction model for grousered rover wheels on loose soil."""

__version__ = "0.1.0"
