"""snake_autonomy.evaluation"""
