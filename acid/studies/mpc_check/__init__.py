"""The paper's closed-loop scenarios (``acid mpc-check``, Figs. 7-10: the NMPC on the model,
on the plant, and the CAV case) and their regression references."""
