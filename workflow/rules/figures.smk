# The figures: one rule and one script per figure; they read tables only, so a plotting
# edit never re-runs a simulation or a solve.


# Fig. 1: beta(r) and m(r) from the theory table.
rule fig1:
    input:
        exponents="results/theory/exponents.parquet",
    output:
        "results/figures/fig1.pdf",
        report(
            "results/figures/fig1.png",
            caption="../report/fig1.rst",
            category="Figures",
        ),
    log:
        "logs/figures/fig1.log",
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=5,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        dpi=config["figures"]["png_dpi"],
        code=code(stages.PLOTTING, "figures/fig1.py"),
    script:
        "../../scripts/figures/fig1.py"


# Fig. 2: q(r) from the theory table.
rule fig2:
    input:
        exponents="results/theory/exponents.parquet",
    output:
        "results/figures/fig2.pdf",
        report(
            "results/figures/fig2.png",
            caption="../report/fig2.rst",
            category="Figures",
        ),
    log:
        "logs/figures/fig2.log",
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=5,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        dpi=config["figures"]["png_dpi"],
        code=code(stages.PLOTTING, "figures/fig2.py"),
    script:
        "../../scripts/figures/fig2.py"


# Fig. 3: the exact P(x,v) at r = 1/2 and 1/3.
rule fig3:
    input:
        distributions=expand("results/exact/r{r}/distribution.parquet", r=EXACT_LABELS),
    output:
        "results/figures/fig3.pdf",
        report(
            "results/figures/fig3.png",
            caption="../report/fig3.rst",
            category="Figures",
        ),
    log:
        "logs/figures/fig3.log",
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=5,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        dpi=config["figures"]["png_dpi"],
        code=code(stages.PLOTTING, "figures/fig3.py"),
    script:
        "../../scripts/figures/fig3.py"


# Fig. 4: P(0,v), the asymptotic forms and the solver, r of figures.fig4.
rule fig4:
    input:
        simulation=expand(
            "results/simulation/r{r}/p0v.parquet", r=figure_labels("fig4")
        ),
        solver=expand("results/solver/r{r}/p0v.parquet", r=figure_labels("fig4")),
        fits=expand("results/fits/r{r}.parquet", r=figure_labels("fig4")),
    output:
        "results/figures/fig4.pdf",
        report(
            "results/figures/fig4.png",
            caption="../report/fig4.rst",
            category="Figures",
        ),
    log:
        "logs/figures/fig4.log",
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=5,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        dpi=config["figures"]["png_dpi"],
        code=code(stages.PLOTTING, "figures/fig4.py"),
    script:
        "../../scripts/figures/fig4.py"


# Fig. 5: P(0,v) against the exact solution, r of figures.fig5.
rule fig5:
    input:
        simulation=expand(
            "results/simulation/r{r}/p0v.parquet", r=figure_labels("fig5")
        ),
        exact=expand("results/exact/r{r}/p0v.parquet", r=figure_labels("fig5")),
    output:
        "results/figures/fig5.pdf",
        report(
            "results/figures/fig5.png",
            caption="../report/fig5.rst",
            category="Figures",
        ),
    log:
        "logs/figures/fig5.log",
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=5,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        dpi=config["figures"]["png_dpi"],
        code=code(stages.PLOTTING, "figures/fig5.py"),
    script:
        "../../scripts/figures/fig5.py"


# Fig. 6: <x>, Delta x, I against r: solver grid, simulated r, exact values.
rule fig6:
    input:
        grid="results/solver/time_averages.parquet",
        simulation=expand("results/simulation/r{r}/summary.parquet", r=RESTITUTION),
        solver=expand("results/solver/r{r}/summary.parquet", r=RESTITUTION),
        exact=expand("results/exact/r{r}/summary.parquet", r=EXACT_LABELS),
    output:
        "results/figures/fig6.pdf",
        report(
            "results/figures/fig6.png",
            caption="../report/fig6.rst",
            category="Figures",
        ),
    log:
        "logs/figures/fig6.log",
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=5,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        dpi=config["figures"]["png_dpi"],
        code=code(stages.PLOTTING, "figures/fig6.py"),
    script:
        "../../scripts/figures/fig6.py"


# Fig. 7: (simulation - solver) / sigma of P(0,v), every simulated r.
rule fig7:
    input:
        simulation=expand("results/simulation/r{r}/p0v.parquet", r=RESTITUTION),
        solver=expand("results/solver/r{r}/p0v.parquet", r=RESTITUTION),
    output:
        "results/figures/fig7.pdf",
        report(
            "results/figures/fig7.png",
            caption="../report/fig7.rst",
            category="Figures",
        ),
    log:
        "logs/figures/fig7.log",
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=5,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        dpi=config["figures"]["png_dpi"],
        code=code(stages.PLOTTING + stages.COMPARISON, "figures/fig7.py"),
    script:
        "../../scripts/figures/fig7.py"


# Fig. 8: P(x,v) against v for any r (the paper's Fig. 3), r of figures.fig8.
rule fig8:
    input:
        solver=expand(
            "results/solver/r{r}/distribution.parquet", r=figure_labels("fig8")
        ),
        simulation=expand(
            "results/simulation/r{r}/distribution.parquet", r=figure_labels("fig8")
        ),
        exact=expand("results/exact/r{r}/distribution.parquet", r=EXACT_LABELS),
    output:
        "results/figures/fig8.pdf",
        report(
            "results/figures/fig8.png",
            caption="../report/fig8.rst",
            category="Figures",
        ),
    log:
        "logs/figures/fig8.log",
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=5,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        dpi=config["figures"]["png_dpi"],
        code=code(stages.PLOTTING, "figures/fig8.py"),
    script:
        "../../scripts/figures/fig8.py"


# Fig. 9: P(x) for every r of restitution: solver, simulation, exact.
rule fig9:
    input:
        solver=expand("results/solver/r{r}/position.parquet", r=RESTITUTION),
        simulation=expand("results/simulation/r{r}/position.parquet", r=RESTITUTION),
        exact=expand("results/exact/r{r}/position.parquet", r=EXACT_LABELS),
    output:
        "results/figures/fig9.pdf",
        report(
            "results/figures/fig9.png",
            caption="../report/fig9.rst",
            category="Figures",
        ),
    log:
        "logs/figures/fig9.log",
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=5,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        dpi=config["figures"]["png_dpi"],
        code=code(stages.PLOTTING, "figures/fig9.py"),
    script:
        "../../scripts/figures/fig9.py"


# Fig. 10: the flight-time distribution, r of figures.fig10.
rule fig10:
    input:
        solver=expand(
            "results/solver/r{r}/flight_time.parquet", r=figure_labels("fig10")
        ),
        summary=expand("results/solver/r{r}/summary.parquet", r=figure_labels("fig10")),
        simulation=expand(
            "results/simulation/r{r}/flight_time.parquet", r=figure_labels("fig10")
        ),
    output:
        "results/figures/fig10.pdf",
        report(
            "results/figures/fig10.png",
            caption="../report/fig10.rst",
            category="Figures",
        ),
    log:
        "logs/figures/fig10.log",
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=5,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        dpi=config["figures"]["png_dpi"],
        code=code(stages.PLOTTING, "figures/fig10.py"),
    script:
        "../../scripts/figures/fig10.py"


# Fig. 11: the return-speed law against the simulated bounce pairs, r of figures.fig11.
rule fig11:
    input:
        solver=expand(
            "results/solver/r{r}/return_speed.parquet", r=figure_labels("fig11")
        ),
        simulation=expand(
            "results/simulation/r{r}/return_speed.parquet", r=figure_labels("fig11")
        ),
    output:
        "results/figures/fig11.pdf",
        report(
            "results/figures/fig11.png",
            caption="../report/fig11.rst",
            category="Figures",
        ),
    log:
        "logs/figures/fig11.log",
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=5,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        dpi=config["figures"]["png_dpi"],
        outgoing_speeds=config["figures"]["return_speeds"],
        code=code(stages.PLOTTING, "figures/fig11.py"),
    script:
        "../../scripts/figures/fig11.py"


# Fig. 12: the relaxation of the bounce chain, the solver's lambda_2 over r against the
# simulated decay rates and correlations at every simulated r.
rule fig12:
    input:
        relaxation="results/theory/relaxation.parquet",
        simulation=expand("results/simulation/r{r}/bounce_chain.parquet", r=RESTITUTION),
    output:
        "results/figures/fig12.pdf",
        report(
            "results/figures/fig12.png",
            caption="../report/fig12.rst",
            category="Figures",
        ),
    log:
        "logs/figures/fig12.log",
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=5,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        dpi=config["figures"]["png_dpi"],
        code=code(stages.PLOTTING, "figures/fig12.py"),
    script:
        "../../scripts/figures/fig12.py"


# Fig. 13: the collapse of the solver's P(0,v) onto its quasi-elastic limit as r -> 1.
rule fig13:
    input:
        "results/theory/quasi_elastic.parquet",
    output:
        "results/figures/fig13.pdf",
        report(
            "results/figures/fig13.png",
            caption="../report/fig13.rst",
            category="Figures",
        ),
    log:
        "logs/figures/fig13.log",
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=5,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        dpi=config["figures"]["png_dpi"],
        code=code(stages.PLOTTING, "figures/fig13.py"),
    script:
        "../../scripts/figures/fig13.py"
