"""The car study from the command line: a folder of a car's logs in, the cabin and A/C power
fitted on estimation trips, scored on held-out trips, and the economic NMPC on a trip replay.

:mod:`acid.studies.car.power` holds the leave-trips-out validation of the power output and
its bound (what any regressor on the same logged channels reaches on unseen trips).
"""
