"""icosim.studies"""
