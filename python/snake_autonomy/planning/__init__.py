"""snake_autonomy.planning"""
