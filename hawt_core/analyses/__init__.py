"""The analyses: pipelines from a turbine to result objects (blade modes on the spinning
hub, Floquet modal analysis of the whole turbine, Campbell sweeps)."""
