"""foam"""
