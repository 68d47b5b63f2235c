"""icosim.problems.linear"""
