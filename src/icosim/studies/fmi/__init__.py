"""icosim.studies.fmi"""
