"""thinfilm"""
