"""Cities: any road network and day of trips, imported into a city folder rpbench runs scenarios on.

:mod:`.roads` reads a network (an OSMnx GraphML, or node and arc tables) and keeps what rpbench can drive
on; :mod:`.trips` reads a trip table and places each trip on the network; :mod:`.importer` writes the city
folder (:mod:`.folder`), which :func:`read_city` reads back, checked.  The method and the folder:
docs/cities.md.
"""
