"""The scene stages, one file each (``scene/stage.py`` says what a stage declares)."""
