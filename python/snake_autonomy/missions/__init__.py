"""snake_autonomy.missions"""
