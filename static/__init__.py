"""The landing page that frames the viser scene, installed as package data of ``app``."""
