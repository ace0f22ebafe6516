"""The short summary ``offline-prog plan`` prints at the end, read from report.json."""

from __future__ import annotations

from rich.console import Console


def print_summary(console: Console, report: dict, files: dict, seconds: float) -> None:
    """A few lines: path and fit, motion, robot, clearance, cusps, the files, the time."""
    fit, motion, traj = report["fit"], report["motion"], report["trajectory"]
    console.print(
        f"[bold]{report['name'] or report['cell']}[/bold]  robot {report['robot']}, "
        f"tool {report['tool']}, part {report['part']}"
    )
    console.print(
        f"  path      {report['path']['length_m'] * 1e3:.1f} mm "
        f"({report['path']['source']}, {'closed' if report['path']['closed'] else 'open'})"
        f", fit degree {fit['degree']} with {fit['n_control_points']} control points, "
        f"max error {fit['max_error_mm']:.4f} mm, RMS {fit['rms_error_mm']:.4f} mm"
    )
    reduced = " (reduced: short path)" if motion["top_speed_reduced"] else ""
    console.print(
        f"  motion    {motion['top_speed_m_s'] * 1e3:.1f} mm/s at the "
        f"{motion['speed_reference']}{reduced}, cycle {traj['duration_s']:.3f} s, "
        f"{traj['n_samples']} samples, speed error "
        f"{traj['chord_speed_max_error_rel'] * 100:.4f} %"
    )
    print_payload_warning(console, report)
    robot = report["robot_motion"]
    reductions = robot["speed_reductions"]
    console.print(
        f"  robot     branch {robot['branch']}, min joint-limit margin "
        f"{robot['min_joint_limit_margin_deg']:.1f}°, largest joint step "
        f"{robot['largest_joint_step']['step_deg']:.3f}°, "
        + (
            f"speed lowered on {len(reductions)} stretch(es), down to "
            f"{min(r['speed_m_s'] for r in reductions) * 1e3:.1f} mm/s"
            if reductions
            else "process speed held everywhere"
        )
    )
    distance = report["min_distance_m"]
    closest = report["closest_pair"]
    console.print(
        "  clearance "
        + (
            "no checked pairs"
            if distance is None
            else f"min distance {distance * 1e3:.1f} mm ({' vs '.join(closest['pair'])} at "
            f"σ={closest['sigma_m']:.3f} m), "
            + ("collision-free" if report["collision_free"] else "FAILS")
        )
    )
    cusps = report["cusps"]
    console.print(
        f"  cusps     {len(cusps)}"
        + (
            "  " + ", ".join(f"{c['kind']} at σ={c['sigma_m']:.3f} m" for c in cusps[:5])
            if cusps
            else ""
        )
    )
    for name, path in files.items():
        console.print(f"  {name:<9} {path}")
    console.print(f"done in {seconds:.2f} s; outputs in [bold]{files['report'].parent}[/bold]")


def print_payload_warning(console: Console, report: dict) -> None:
    """The payload line when the programs do not set it (a seam's or a job's report)."""
    if not report["payload"]["set"]:
        console.print(
            f"  [bold yellow]payload   {report['payload']['warning']}[/bold yellow]",
            highlight=False,
        )


def print_quality(console: Console, quality: dict | None) -> None:
    """One line: the process model's share of the process length within its band (and
    with compensation off, for the bead), its range and the stretches outside."""
    if not quality:
        return
    low, high, unit = *quality["band"], quality["unit"]
    share = quality["share_within_band"]
    text = "nothing dispensed" if share is None else f"{100 * share:.1f} %"
    if quality.get("share_within_band_uncompensated") is not None:
        text += f" (compensation off: {100 * quality['share_within_band_uncompensated']:.1f} %)"
    spread = quality["min"] is not None and f" (from {quality['min']:.4g} to {quality['max']:.4g})"
    console.print(
        f"  quality   {quality['model']}: {text} of the process length within "
        f"{low:g} .. {high:g} {unit}{spread or ''}; {quality['n_stretches_outside']} stretches "
        "outside (report.json quality)",
        highlight=False,
    )


def print_job_summary(console: Console, report: dict, files: dict, seconds: float) -> None:
    """A few lines for a job: order, cycle time split, each seam, links, clearance."""
    job = report["job"]
    console.print(
        f"[bold]{report['name'] or report['cell']}[/bold]  robot {report['robot']}, "
        f"tool {report['tool']}, part {report['part']}: {len(report['seams'])} "
        + ("seam" if len(report["seams"]) == 1 else "seams")
    )
    print_payload_warning(console, report)
    order = ", ".join(f"{o['seam']} ({o['direction']})" for o in job["order"])
    console.print(
        f"  order     {order} ({job['order_mode']}, {job['order_method']}; estimated "
        f"saving {job['estimated_saving_s']:.2f} s against the given order)"
    )
    search = job["order_search"]
    if search["method"] == "heuristic":
        console.print(
            f"  search    {search['rounds']} rounds, {search['used_link_estimates'] / 1e6:.1f} "
            f"of {search['budget_link_estimates'] / 1e6:.1f} M link estimates in "
            f"{search['time_s']:.2f} s, stopped: {search['stopped']}; estimated air "
            f"{search['air_time_s']:.2f} s from {search['start_air_time_s']:.2f} s (no order "
            f"below {search['lower_bound_s']:.2f} s)"
        )
    console.print(
        f"  cycle     {job['cycle_time_s']:.2f} s: process {job['process_time_s']:.2f} s, "
        f"air {job['air_time_s']:.2f} s (links {job['link_time_s']:.2f} s, approach and "
        f"retract {job['approach_retract_time_s']:.2f} s)"
    )
    for seam in report["seams"]:
        console.print(
            f"  seam      {seam['seam']}: {seam['path']['length_m'] * 1e3:.1f} mm, "
            f"{seam['trajectory']['duration_s']:.2f} s, fit max error "
            f"{seam['fit']['max_error_mm']:.4f} mm"
        )
    for link in report["links"]:
        console.print(f"  link      {link['name']}: {link['method']}, {link['duration_s']:.2f} s")
    print_quality(console, report.get("quality"))
    distance = report["min_distance_m"]
    console.print(
        "  clearance "
        + ("no checked pairs" if distance is None else f"min distance {distance * 1e3:.1f} mm, ")
        + ("collision-free" if report["collision_free"] else "FAILS")
    )
    stages = ", ".join(f"{k} {v:.1f} s" for k, v in report["timings_s"].items() if v >= 0.05)
    console.print(f"  time      {stages}", highlight=False)
    for name, path in files.items():
        console.print(f"  {name:<9} {path}")
    console.print(f"done in {seconds:.2f} s; outputs in [bold]{files['report'].parent}[/bold]")
