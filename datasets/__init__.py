"""acid's shipped data (drive cycles, example maps, the data format), installed as the
package ``acid.datasets`` and found with ``importlib.resources`` (``acid.signals.datasets_dir``).
"""
