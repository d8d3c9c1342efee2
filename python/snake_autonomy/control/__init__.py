"""snake_autonomy.control"""
