"""ehlfoam"""
