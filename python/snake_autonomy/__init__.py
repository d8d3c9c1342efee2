"""snake_autonomy: autonomy stack for modular snake robots (COBRA first)."""
