"""The committed reference report of the study, installed as package data of ``app``."""
