"""icosim.problems"""
