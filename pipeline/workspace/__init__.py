"""The workspace: position grids, the criteria (one module per family, one registry), the
verdict rule, the vectorised kernel over chunks of poses and its one level of parallelism, the
line simulations, the literal per-pose reference; ``compute`` turns a composed config into a
problem and a workspace table (Arrow columns built by ``arrow``, without pandas)."""
