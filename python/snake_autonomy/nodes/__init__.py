"""snake_autonomy.nodes"""
