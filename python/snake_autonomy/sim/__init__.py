"""snake_autonomy.sim"""
