"""Further `frf-ident` subcommands: each entry is (help, add_arguments); the handler is
registered with :func:`frf_ident.cli.command`. Kept apart from cli.py so each command's
imports load only when it runs. Other modules add their own entries with
:func:`subcommand` and are imported at the bottom of this file."""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Callable

from frf_ident.errors import FrfIdentInputError

SUBCOMMANDS: dict[str, tuple[str, Callable]] = {}


def subcommand(name: str, help_text: str):
    """Register the argument builder of a subcommand (its handler: @cli.command(name))."""
    def register(add_args: Callable[[argparse.ArgumentParser], None]):
        SUBCOMMANDS[name] = (help_text, add_args)
        return add_args
    return register


def _say(msg: str) -> None:
    print(msg, flush=True)


# --- identify ---------------------------------------------------------------------------------

@subcommand('identify', 'run the identification experiments in closed loop, record a bag')
def _identify_args(p: argparse.ArgumentParser) -> None:
    p.add_argument('--model', type=Path, help='model file (default: the embedded 3-axis model)')
    p.add_argument('--plant', help="plant plug-in 'package.module:Class' (default: the model's "
                                   "own simulation)")
    p.add_argument('--out', type=Path, required=True, help='bag directory to create')
    p.add_argument('--procedures', default='multisine,chirp',
                   help='comma list of multisine, chirp (default both)')
    p.add_argument('--realisations', type=int, default=10, help='multisine n_p (paper: 10)')
    p.add_argument('--periods', type=int, default=5, help='multisine n_q (paper: 5)')
    p.add_argument('--resolution', type=float, default=0.25,
                   help='multisine frequency resolution [Hz] (paper: 0.1 -> 12.3 s periods)')
    p.add_argument('--no-compensation', action='store_true',
                   help='skip the constant-velocity run (no periodic-disturbance compensation)')
    p.add_argument('--chirp-duration', type=float, default=20.0)
    p.add_argument('--max-iterations', type=int, default=6)
    p.add_argument('--seed', type=int, default=0)


def identification_config(args: argparse.Namespace):
    from frf_ident.core.procedures import ChirpConfig, MultisineConfig
    from frf_ident.core.runner import IdentificationConfig
    procs = {s.strip() for s in args.procedures.split(',') if s.strip()}
    unknown = procs - {'multisine', 'chirp'}
    if unknown or not procs:
        raise FrfIdentInputError(f'--procedures {args.procedures!r}: expected a comma list of '
                                 f'multisine, chirp')
    ms = MultisineConfig(n_realisations=args.realisations, n_periods=args.periods,
                         resolution_hz=args.resolution, compensate=not args.no_compensation,
                         seed=args.seed) if 'multisine' in procs else None
    ch = ChirpConfig(duration=args.chirp_duration, max_iterations=args.max_iterations) \
        if 'chirp' in procs else None
    return IdentificationConfig(ms, ch)


def run_identify(model_path, plant_spec, config, out: Path, *, progress=_say):
    """Load, run, and record; returns the Recording (also written to ``out``)."""
    from frf_ident.bag import write_recording
    from frf_ident.core.runner import run_identification
    from frf_ident.model_file import load_model, load_plant
    if out.exists():
        raise FrfIdentInputError(f'{out}: already exists; choose a new bag path (nothing was '
                                 f'overwritten)')
    model, robot, ctrl = load_model(model_path)
    plant = load_plant(plant_spec, model)
    rec = run_identification(plant, ctrl, config, progress=progress,
                             meta={'model': model, 'plant': plant_spec or 'model'})
    write_recording(rec, out)
    return rec


def _identify(args: argparse.Namespace) -> int:
    rec = run_identify(args.model, args.plant, identification_config(args), args.out)
    s = rec.meta['summary']
    if 'multisine' in s:
        m = s['multisine']
        _say(f"multisine: {m['segments']} segments, {m['lines']} lines, period "
             f"{m['period_s']:.3f} s, experiment time {m['experiment_time_s']:.1f} s")
    if 'chirp' in s:
        c = s['chirp']
        for it in c['iterations']:
            _say(f"chirp iteration {it['iteration']}: error to u_des per channel "
                 f"{', '.join(f'{e:.2f}' for e in it['error_db_per_channel'])} dB, "
                 f"max |u| {', '.join(f'{u:.0f}' for u in it['max_abs_torque'])} N m "
                 f"(limits {', '.join(f'{u:.0f}' for u in c['torque_limit'])})")
        _say(f"chirp: {'converged' if c['converged'] else 'NOT converged'} after "
             f"{c['final_iteration']} iterations, experiment time {c['experiment_time_s']:.1f} s")
    _say(f"total experiment time {s['total_experiment_time_s']:.1f} s (simulated in "
         f"{s['wall_time_s']:.1f} s); bag: {args.out}")
    return 0


# --- estimate ---------------------------------------------------------------------------------

@subcommand('estimate', 'estimate FRFs offline from a bag')
def _estimate_args(p: argparse.ArgumentParser) -> None:
    p.add_argument('bag', type=Path)
    p.add_argument('--out', type=Path, required=True, help='output directory')
    p.add_argument('--joints', help='comma list of joint names to analyse (default: all)')
    p.add_argument('--t-range', type=float, nargs=2, metavar=('START', 'END'),
                   help='analyse only this time range [s]')
    p.add_argument('--primary', default=None,
                   help='which estimate goes to frf.json (default: multisine, else chirp)')
    p.add_argument('--stream', action='store_true',
                   help='read the bag window by window in bounded memory (automatic when the '
                        'bag would need more than --max-memory)')
    p.add_argument('--max-memory', type=float, default=None, metavar='MB',
                   help='memory the in-memory reader may use before streaming (default: a '
                        'quarter of RAM, at most 4096)')
    p.add_argument('--window', type=float, default=300.0, metavar='S',
                   help='streaming block length for bags without experiment descriptors '
                        '[s] (default 300; must hold a few multisine periods or a whole chirp)')
    g = p.add_argument_group('excitation of a bag without /frf/experiment descriptors '
                             '(what `detected:` prints; replaces detection)')
    g.add_argument('--input', metavar='JOINT', help='the excited joint (the only input)')
    kind = g.add_mutually_exclusive_group()
    kind.add_argument('--multisine-period', type=float, metavar='SECONDS',
                      help='multisine period [s]; block and lines are found in the data')
    kind.add_argument('--chirp', type=float, nargs=2, metavar=('F_LOW', 'F_HIGH'),
                      help='exponential chirp from F_LOW to F_HIGH [Hz] (needs --chirp-time)')
    g.add_argument('--band', type=float, nargs=2, metavar=('F_LOW', 'F_HIGH'),
                   help='analyse only the multisine lines in this band [Hz]')
    g.add_argument('--chirp-time', type=float, nargs=2, metavar=('T0', 'T1'),
                   help='sweep start and end [s from the first analysed sample]')


def excitation_options(args: argparse.Namespace):
    """The --input/--multisine-period/--band/--chirp/--chirp-time options of `estimate`."""
    from frf_ident.core.foreign import ExcitationOptions
    tup = (lambda v: tuple(v) if v is not None else None)
    return ExcitationOptions(input=args.input, multisine_period=args.multisine_period,
                             band=tup(args.band), chirp=tup(args.chirp),
                             chirp_time=tup(args.chirp_time))


def _read_estimates(bag: Path, joints, t_range, options, stream: bool | None, max_memory_mb,
                    window_s: float, progress):
    """(estimates, timing report, experiment summary, streaming stats or None)."""
    from frf_ident import streaming
    if max_memory_mb is not None and not max_memory_mb > 0:
        raise FrfIdentInputError(f'--max-memory {max_memory_mb}: expected a size in MB > 0')
    if not window_s > 0:
        raise FrfIdentInputError(f'--window {window_s}: expected a block length in s > 0')
    budget = streaming.default_memory_budget() if max_memory_mb is None else \
        int(max_memory_mb * (1 << 20))
    if stream or streaming.needs_streaming(bag, budget):
        res = streaming.stream_estimate(bag, joints=joints, t_range=t_range, block_s=window_s,
                                        options=options, progress=progress,
                                        bar=sys.stderr.isatty())
        st = res.stats
        progress(f'streamed {sum(st.messages.values())} messages in {st.windows} windows, '
                 f'at most {st.peak_rows} held at once')
        return res.estimates, res.timing, res.meta.get('summary', {}), {
            'windows': st.windows, 'peak_rows': st.peak_rows, 'messages': st.messages,
            'budget_bytes': budget}
    from frf_ident.bag import read_recording
    from frf_ident.core.closed_loop import estimate_recording
    rec, timing = read_recording(bag, joints=joints, t_range=t_range)
    for line in timing.summary():
        progress(line)
    return estimate_recording(rec, options=options), timing, rec.meta.get('summary', {}), None


def estimate_bag(bag: Path, out: Path, *, joints=None, t_range=None, primary=None,
                 options=None, stream: bool | None = None, max_memory_mb: float | None = None,
                 window_s: float = 300.0, progress=_say) -> dict:
    """Estimate every FRF the bag supports and write DIR/frf.json, estimates.json,
    summary.json and bode.png. Refusals (:class:`EstimationError`) name the bag and leave
    ``out`` untouched; ``options`` (ExcitationOptions) replace detection; ``stream`` (or a
    bag over ``max_memory_mb``) reads it window by window (:mod:`frf_ident.streaming`)."""
    from frf_ident.errors import EstimationError
    from frf_ident.report.figures import bode_figure
    try:
        estimates, timing, experiment, streamed = _read_estimates(
            bag, joints, t_range, options, stream, max_memory_mb, window_s, progress)
    except EstimationError as exc:
        raise EstimationError(f'{bag}: {exc}') from None
    if streamed is not None:
        for line in timing.summary():
            progress(line)
    for line in next(iter(estimates.values())).meta.get('detected', []):
        progress(f'detected: {line}')
    key = primary or ('multisine' if 'multisine' in estimates else next(iter(estimates)))
    if key not in estimates:
        raise FrfIdentInputError(f'--primary {key!r}: the bag supports {sorted(estimates)}')
    out.mkdir(parents=True, exist_ok=True)
    frf = estimates[key]
    doc = frf.to_dict()
    doc['estimate'] = key
    (out / 'frf.json').write_text(json.dumps(doc))
    (out / 'estimates.json').write_text(json.dumps({k: v.to_dict()
                                                    for k, v in estimates.items()}))
    summary = {'bag': str(bag), 'primary': key, 'estimates': sorted(estimates),
               'timing': timing.to_dict(), 'experiment': experiment, 'streaming': streamed}
    (out / 'summary.json').write_text(json.dumps(summary, indent=1, default=str))
    pairs = [(k, v) for k, v in estimates.items() if k in ('multisine', 'chirp')]
    bode_figure(dict(pairs or [(key, frf)]), out / 'bode.png',
                title=f'{bag.name}: {" vs ".join(k for k, _ in pairs) or key}')
    progress(f'wrote {out / "frf.json"} ({key}: {frf.noutputs}x{frf.ninputs} channels, '
             f'{frf.freq_hz.size} lines) and {out / "bode.png"}')
    return estimates


def _estimate(args: argparse.Namespace) -> int:
    joints = [j.strip() for j in args.joints.split(',')] if args.joints else None
    estimate_bag(args.bag, args.out, joints=joints,
                 t_range=tuple(args.t_range) if args.t_range else None, primary=args.primary,
                 options=excitation_options(args), stream=args.stream,
                 max_memory_mb=args.max_memory, window_s=args.window)
    return 0


def _register_handlers() -> None:
    from frf_ident.cli import command
    command('identify')(_identify)
    command('estimate')(_estimate)


_register_handlers()


# --- import (frf_ident.io) --------------------------------------------------------------------
from frf_ident.io import cli_import as _cli_import  # noqa: E402,F401  (registers 'import')
from frf_ident import diagnose_cmd  # noqa: E402,F401
from frf_ident import demo_cmd  # noqa: E402,F401
