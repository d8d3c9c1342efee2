"""snake_autonomy.estimation"""
