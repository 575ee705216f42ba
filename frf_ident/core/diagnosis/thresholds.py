# Copyright 2026 frf_ident developers
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.
"""
Hold every threshold and default of the diagnosis, each with its meaning and its origin.

One place for the numbers both routes (experiments, time series) decide by. "Calibrated" names
the check that pins a value: the ripple constants come from a Monte-Carlo benchmark, the rest
were set by hand and are held by the diagnosis sweeps (``python -m benchmarks.diagnosis N
SEED``: recall, false alarms, clean scenes) and the regression scenes in
test/app/test_diagnose_scenes.py; a value changed here must leave those unchanged.
"""

# --- analysis band ---------------------------------------------------------------------------

#: [Hz] low-pass of the inverse-dynamics residual and of every regressor where no band is chosen
#: from the record (experiments route, the time-series metrics of other records, the
#: least-squares baseline of issue #41); and the narrowest band :func:`.band.analysis_band`
#: chooses: the sweeps and the regression scenes are calibrated at it (below the first joint
#: resonance of the demo and KUKA models). Fixed by hand.
FC_HZ = 20.0
#: the analysis band of a time-series record holds this share of the power of the motion (the
#: measured velocity, on the lines where it stands BAND_SNR above its noise floor). The
#: velocity, not the acceleration: a broadband shake (a torque dither, the pulses of the EMPS
#: validation run) carries a share of the acceleration's power up to the Nyquist frequency but
#: next to none of the velocity's. Set by hand: 14 Hz on EMPS (bang-bang trajectories), 3 Hz
#: on KUKA A axes 1-3, 1.5 Hz on the dithered reference-plant record: all keep FC_HZ
#: (test/core/diagnosis/test_band.py)
BAND_MOTION_SHARE = 0.999
#: a velocity line counts as motion above this many times the white velocity noise floor
#: (the median PSD between 0.6 and 0.95 of Nyquist; 10 dB)
BAND_SNR = 10.0
#: the analysis band ends at most at this share of the sample rate, so that the residual scan
#: above it keeps at least the band up to RESONANCE_TOP of the sample rate
BAND_MAX_SHARE = 0.25

# --- residual spectrum above the analysis band (resonance.py) ---------------------------------

#: probability that a residual whose spectrum is smooth (no resonance) is reported with one,
#: per axis and record. The threshold is the chi-square tail of the Welch estimate against its
#: local median; measured on white and rising noise (test/core/diagnosis/test_band.py: 600
#: scans each of 10 s at 1 kHz, 0 and 2 alarms where 0.6 are expected)
RESONANCE_FALSE_ALARM = 1e-3
#: [s] Welch segment of the residual spectrum (1 Hz lines; a resonance of 3 % damping at 35 Hz
#: is 2 Hz wide at half power)
RESONANCE_SEGMENT_S = 1.0
#: lines of the running median that gives the residual's local noise floor (a peak narrower
#: than half of it does not lift the floor)
RESONANCE_FLOOR_LINES = 41
#: the scan ends at this share of the sample rate (the anti-alias filters' band edge)
RESONANCE_TOP = 0.45
#: resonances listed per axis, strongest first
RESONANCE_MAX = 5
#: a peak at most this many lines wide at half power is a line (a Hann window makes a sine
#: 1.44 lines wide), wider a resonance (3 % damping at 39 Hz is 2.3 Hz wide; the test plant's
#: mode measures 3.0 Hz, EMPS' 50 and 100 Hz mains lines 1.7 and 1.6). Set by hand between
#: the two (test/core/diagnosis/test_band.py)
RESONANCE_MIN_WIDTH_LINES = 2.0

# --- what locks a line above the analysis band (timeseries/line_lock.py) ---------------------

#: a steady stretch of the motion: the speed (low-passed at LINE_SPEED_HZ) stays within this
#: share of the stretch's first speed ...
LINE_STEADY_SHARE = 0.05
#: ... for at least this long [s]; stretches whose speeds agree within LINE_STEADY_SHARE form
#: one steady speed (EMPS: 0.083 m/s eight times 0.64 s, 0.125 m/s eight times 1.01 s)
LINE_MIN_RUN_S = 0.4
#: [Hz] low-pass of the speed that finds the steady stretches
LINE_SPEED_HZ = 5.0
#: probability that noise alone puts a PSD line (of the three around a predicted frequency)
#: above the threshold at one steady speed: a line "is there" above it. The chi-square
#: threshold of resonance.peak_threshold with the speed's own Welch windows, 3 lines tested
LINE_LOCK_FALSE_ALARM = 1e-3
#: a steady speed tells the hypotheses apart only where a position-locked line would lie at
#: least this many lines away from the line's own frequency
LINE_LOCK_MIN_SHIFT_LINES = 2.0

# --- the sensor read from the record (sensor.py) -----------------------------------------------

#: a position reading is quantised when at least this share of its changes lie within
#: SENSOR_GRID_TOL counts of a whole number of counts (noise-free continuous values: a share
#: near 2 SENSOR_GRID_TOL; the reference plant's encoders and EMPS' 5e-8 m: 1.0)
SENSOR_GRID_SHARE = 0.99
SENSOR_GRID_TOL = 0.01
#: ... judged on at least this many changes of the position
SENSOR_MIN_STEPS = 100
#: a velocity is the difference of two readings over a sample when it takes the weights 1
#: and 0 (within this) on the backward and the next difference ...
SENSOR_TAP_TOL = 0.05
#: ... and the backward difference leaves less than this share of the RMS the central
#: difference leaves (the reference plant's differenced encoders: under 0.1; KUKA's drive
#: velocity, filtered: 0.59, taps not 1 / 0; EMPS' velocity, the central difference of the
#: import map: infinite). Set by hand between them (test/core/diagnosis/test_sensor.py)
SENSOR_DIFF_EXPLAINS = 0.5
#: a model file's encoder_resolution within this share of the one read is no effect
SENSOR_RESOLUTION_MATCH = 0.1

# --- acceptance of an effect (both routes) ----------------------------------------------------

#: an effect must remove this share of its axis' misfit above the noise floor; and an axis whose
#: held-out misfit left is this share of the nominal one (and above UNEXPLAINED_RATIO) is
#: unexplained. Set by hand; held by the sweeps' false-alarm rate.
MIN_SHARE = 0.10
#: ... and the drop must exceed this many standard deviations of the misfit under noise alone,
#: or this many standard errors of the two models' paired differences on the fit part
#: (experiments/acceptance.py ``passes``); also the move of the held-out misfit at doubled
#: substeps that calls a simulation too coarse.
MIN_Z = 3.0
#: the integrator check doubles ``simulation.substeps`` of the extended model while the doubled
#: step still moves an axis' held-out misfit by MIN_Z, up to this many substeps (the plant's
#: cost grows in proportion; the demo robot settles at 2, see docs/model_file.md)
MAX_SUBSTEPS = 16
#: experiments route: an effect is kept only where its held-out gain (the misfit of its axis
#: without it minus with it, per loss term in the standard errors of the paired differences
#: over the held-out FRF lines and time blocks, combined over the terms by Stouffer's rule
#: weighted by the z each term would show were the effect true, with the torque and velocity
#: terms' correlation, a term the model leaves above
#: UNEXPLAINED_RATIO of its own floor counting only for the effect) exceeds this many
#: standard errors of noise alone (experiments/noise_gain.py). Set to MIN_Z's 3: an effect
#: that buys nothing passes with the normal tail, 0.13 %; 0.10 % in the Monte Carlo of
#: test/core/diagnosis/test_noise_gain.py (pieces correlated as measured on the nominal
#: sensor scenes); the rate and the z's spread measured on those scenes:
#: docs/diagnosis/experiments.md, "Held-out gain over noise". The same threshold holds the
#: gain over the largest standard error any noise gives the two misfits (``bound_z``), and
#: the power below which the held-out part cannot show an effect and does not judge it
#: (``HeldOutGain.can_show``: the z it would give the effect were it true)
HELD_OUT_GAIN_Z = 3.0
#: a friction candidate stage 1 rejected on an axis is offered again after the axis' joint
#: refit where the refit lowered the axis' misfit by this factor or more (its share was judged
#: against the misfit before: later_passes.friction_after_refit). Set by hand at 4, the same factor
#: as UNEXPLAINED_RATIO: a refit that moves an axis by less left its candidates judged on about
#: the misfit they were judged on. Where it acts: the capped-chirp iiwa 14 scene of
#: test/app/test_diagnose_mjcf.py (joint2 34.4 -> 7.1 floors, its motor damping taken then);
#: the make-test diagnosis scenes pass unchanged with it
REFIT_REOFFER_FALL = 4.0
#: [s] blocks of the held-out torque and velocity whose mean squared errors are the pieces of
#: the gain. On the demo record the ripple's torque gain has a standard error of 0.008 /
#: 0.017 / 0.020 / 0.019 noise floors from blocks of 0.1 / 0.5 / 1 / 2 s; set at 1 s. On the
#: nominal sensor scenes neighbouring 1 s blocks anticorrelate (-0.25 at lag 1: the loop's
#: integrator pulls a block's mean error back in the next), which HELD_OUT_GAIN_LAGS takes in
HELD_OUT_GAIN_BLOCK_S = 1.0
#: neighbouring pieces (FRF lines, time blocks) whose autocovariance enters a term's standard
#: error of the held-out gain, with Bartlett's weights (experiments/noise_gain.py ``paired``).
#: Measured on null effects of 12 nominal sensor scenes (144, docs/diagnosis/experiments.md):
#: the z's spread per term multisine / chirp / torque / velocity 1.09 / 1.24 / 0.69 / 0.71
#: with 0 lags (chirp lines +0.08 at lag 1, +0.04 at 2; blocks -0.25 at 1), 1.04 / 1.10 /
#: 0.86 / 0.84 with 2; more lags make the estimate noisier (a heavier tail) for little
HELD_OUT_GAIN_LAGS = 2
#: held-out misfit above this many noise floors (experiments: misfit units; time series: NRMSE^2
#: over its noise floor) is clearly above noise: unexplained, or a friction reading to refit.
#: Set by hand; held by the second-mode scenes (test_unmodelled_second_mode_is_unexplained...).
UNEXPLAINED_RATIO = 4.0

# --- experiments route: evaluator -------------------------------------------------------------

#: relative noise floor assumed where the data give none (noise-free simulated data)
FLOOR_MIN = 1e-6
#: [s] samples this long after a stretch without reference are not compared (the closed loop
#: settles from the measured velocity it followed there)
SETTLE_S = 0.5
#: [s] filtered closed-loop signals carry about one independent sample per this interval (the
#: misfit's standard deviation under noise, :meth:`Evaluator.misfit_sd`)
INDEPENDENT_SAMPLE_S = 0.01
#: simulations the Evaluator keeps (by model): a model checked again within a round is not
#: simulated twice; does not change any result, only the simulation count. Room for a batch
#: simulated in parallel (at most SIM_CACHE - 4 models, :meth:`Evaluator.prefetch`) beside the
#: four models a round checks again
SIM_CACHE = 12
#: fit-part estimates the Evaluator keeps after their simulation left the SIM_CACHE kept ones
#: (a few hundred kB each on the demo bag): stage 2 reads each round against the model so far,
#: whose estimates are then at hand without simulating it again; no result changes
EST_CACHE = 64
#: processes that simulate independent models at once (the candidates of one round, the
#: starting simplex of a joint refit): 2 = the cores of the machine the 30 s goal of the demo
#: diagnosis was set on; 1 = one after the other in this process (the same results: the
#: simulation is deterministic)
SIM_JOBS = 2

# --- experiments route: candidates and refits ---------------------------------------------------

#: t statistic of the residual's position slope that proposes gravity (a clean axis costs no
#: simulation)
GRAVITY_MIN_T = 3.0
#: an effect that removes this share of its axis' misfit dominates it: a dominant friction
#: reading is refitted by simulation before anything else may explain the rest
DOMINANT_SHARE = 0.9
#: |t| of a friction reading that is refitted by simulation when its value fails the acceptance
REFIT_T = 3.0
#: log scale of a linear parameter (inertias, stiffness, damping) the FRF fit must move before
#: a parameter mismatch names it (3 %)
MISMATCH_MIN_LOG = 0.03
#: stage 0 (frequency_fit.py) names a motor inertia, link inertia or stiffness only where its log
#: shift against the nominal simulation's fit is this many standard errors from 0 at both
#: loads (the multisine's and the chirp's); the loads agree within this many combined standard
#: errors. Set by hand to MIN_Z's 3 (a false alarm in about 1 of 370 parameters per load if
#: the errors were Gaussian); held by the clean scenes and the nominal test of
#: test/core/diagnosis/test_frequency_fit.py
FD_MISMATCH_Z = 3.0
#: ... and only where the ML cost per degree of freedom of the axis' own channel in the fit of
#: a weighted estimate (the multisine) stays below this: far above it the model misses
#: structure there (a resonance it lacks), not parameters. Not the chi-square test of
#: core/fit/cost.py: the continuous model fitted to a sampled, closed-loop estimate with a
#: small variance leaves 3-14 on the axes of three reference-plant scenes that have the right
#: structure (mismatched axes 3.4 and 6.7) and up to 1.9 on the nominal simulation; a mode the
#: model lacks 2,300 (joint_3 of the scene of
#: test_unmodelled_second_mode_is_unexplained_on_its_axis; its coupled neighbours 30 and 270).
#: Set by hand between them; held by that test
FD_STRUCTURE_RATIO = 100.0
#: log stiffness difference between the multisine (low load) and the chirp (high load) below
#: which the spring is taken as linear (1 %; stiffening and backlash need more)
LOAD_DEPENDENCE_MIN_LOG = 0.01
#: friction refit range: from 0 to the nominal value plus a friction torque of this share of the
#: axis' 99th-percentile torque
FRICTION_RANGE_SHARE = 0.3
#: FRF-shape evidence read again on axes that took an effect, at most this many rounds
STAGE2_ROUNDS = 3
#: a delay candidate this many samples long makes the friction be read again with it
MIN_DELAY_SAMPLES = 0.1
#: an axis the nominal model holds rigid (experiments/rigid_axes.py) is offered a joint spring
#: where the two-mass joint fits its measured FRFs (both loads, complex log error) this many
#: times better than a rotor inertia alone. Set by hand between the iiwa 14 scene of
#: test/app/test_diagnose_mjcf.py: its elastic joint2 45 x, its rigid joint4 (coupled to
#: joint2, nothing added) 1.09 x
SPRING_COST_RATIO = 4.0
#: ... its spring reading starts from the best of this many antiresonances, log-spaced over
#: the measured band (times three motor-inertia shares)
RIGID_SPRING_GRID = 12
#: ... with this damping ratio (5 %, a geared joint's)
RIGID_SPRING_DAMPING = 0.05
#: rounds of that stage: springs first, then what the axes left read again on top
RIGID_ROUNDS = 3

# --- experiments route: missing structure and second modes: mode_thresholds.py -------------

# --- experiments route: what stays unexplained ------------------------------------------------

#: residual concentrations (bands) listed in an unexplained axis' signature
MAX_BANDS = 3
#: a line's misfit this many noise floors above the floor is "shown" by an estimate
SHOWN = 1.0
#: a band is the run of lines staying above this share of its peak (half the amplitude in dB);
#: further bands must reach this share of the strongest
BAND_SHARE = 0.25
#: |correlation| of the held-out torque residual with a signal (position, velocity, ...) that
#: names it in the signature
CORRELATES_MIN = 0.3

# --- time-series route ------------------------------------------------------------------------

#: false-alarm probability of the F test that admits a regressor group
ALPHA = 1e-3
#: share of the record left out at each end of fit and held-out parts (filter transients)
EDGE = 0.02
#: [s] fit / held-out blocks
BLOCK_S = 0.5
#: every this-many-th block is held out
HOLD_EVERY = 3
#: a block of the standard errors (selection.block_standard_errors) is at least this many
#: integrated correlation times of the fit residual long (BLOCK_S at least): the blocks must
#: be nearly independent for the sandwich. KUKA A's residual is correlated over 0.39-0.76 s
#: (axes 1-3), longer than BLOCK_S. Checked by Monte Carlo on noise correlated over 0.6 s
#: (test/core/diagnosis/test_diagnosis_se_blocks.py)
SE_BLOCK_TAUS = 2.0
#: a link's weight dominates what friction and inertia leave of its axis at this share
#: (the EMPS and KUKA records in test/app/test_diagnose_real.py)
BEARING_SHARE = 0.5
#: an axis is at rest below this many velocity-noise levels ...
REST_NOISE = 0.3
#: ... or below this share of its 95th-percentile speed (the Stribeck region begins)
REST_SHARE = 0.05
#: an axis whose 95th-percentile speed is below this many velocity-noise levels does not move
#: at all (a record of a robot at rest)
STILL_NOISE = 3.0
#: an axis with fewer moving samples than this share in one direction moves one way
ONE_WAY = 0.05
#: [rad] a joint set whose angle sum spans less is no gravity candidate
MIN_TRAVEL = 1e-3

# --- records with gaps ------------------------------------------------------------------------

#: [s] rows bridged over a gap are widened by this on both sides (the low-pass filters' reach)
GAP_GUARD_S = 0.1

# --- torque ripple scan (residual.find_ripple) ------------------------------------------------

#: lowest spatial frequency: this many cycles over the analysed travel
RIPPLE_MIN_CYCLES = 1.5
#: probability that noise alone passes the ripple scan's threshold
RIPPLE_FALSE_ALARM = 1e-3
#: grid points of the running median that gives the local noise level
RIPPLE_LEVEL_WINDOW = 161
#: Monte-Carlo constants of the scan's noise statistic (white noise, 1,500 scans each of 4,000 to
#: 20,000 samples: ``python -m benchmarks ripple_threshold``): the median over the 4x
#: oversampled window is that of about this many independent periodogram values ...
RIPPLE_LEVEL_DOF = 50.0
#: ... and the oversampled scan's maximum behaves as that of this many independent values per
#: resolution cell
RIPPLE_CELL_FACTOR = 1.5

# --- least-squares baseline (baseline.py) -------------------------------------------------------

#: [rad/s] velocity scale of the smooth Coulomb term Fc tanh(qd / LS_TANH_VELOCITY) of the
#: 4-parameter least-squares baseline (issue #41's reference fit)
LS_TANH_VELOCITY = 0.01
#: an axis' extended model "beats" the least-squares baseline on a held-out set unless its
#: time_nrmse exceeds the baseline's by more than this share. Calibrated on the real records:
#: on EMPS the extension (Coulomb, viscous, inertia) is the baseline's own structure and
#: lands at 0.0323 against 0.0320 held out, a tie a strict "<" turned into rejecting the
#: Coulomb friction (reverting to the nominal 0.409); on KUKA A -> B, C the axes whose effects
#: do not generalise are 14-112 % above the baseline (test/app/test_diagnose_real.py)
LS_BASELINE_MARGIN = 0.10

# --- validation records (extrapolation.py) ------------------------------------------------------

#: [deg] a validation record that leaves the fitted configuration range of an axis by more
#: than this is warned about (below it: the same range up to encoder and filter detail)
RANGE_TOLERANCE_DEG = 0.5
#: leave-range-out (extrapolation.leave_range_out): this share of a position term's fitted
#: range held out at each end. On KUKA A axis 3 (gravity sin(q2 + q3 + phi), r = 0.977 with the
#: authors' rigid-body gravity) a tenth passes (residual energy 393 with, 6.8e3 without), a fifth
#: fails (1.9e4 with, 1.1e4 without): phase and constant are nearly one parameter over 40 deg
RANGE_OUT_SHARE = 0.1

# --- standard errors across records (spread.py) -----------------------------------------------

#: the standard errors are widened when the records' differences, in their combined standard
#: errors, are this unlikely under chi-square (one false widening in 20 checks)
SPREAD_ALPHA = 0.05

# --- uncertainty of the diagnosed values (experiments/standard_errors.py, determination.py) ----

#: a parameter whose standard error exceeds this share of its value (after the joint refits)
#: is not determined: within 2 errors the truth then lies between 1/3 and 5/3 of the value (a
#: factor of 3). Held by the sweep ``python -m benchmarks diagnosis_uncertainty``
NOT_DETERMINED_SHARE = 1.0 / 3.0
#: the refits of a parameter on the record's multisine alone and on its chirp alone disagree
#: beyond their errors where they differ by more than this many combined standard errors
#: (MIN_Z's 3: about 1 in 370 pairs by chance if the errors were Gaussian)
REFITS_AGREE_Z = 3.0
#: a parameter trades against another of its axis when their estimates correlate by at
#: least this much (|r|): the joint refit of an unsettled parameter takes those along
TRADE_CORRELATION = 0.5
#: joint refits (Gauss-Newton steps on the parameter and its partners) before an unsettled
#: parameter is reported not determined
SETTLE_ROUNDS = 2
#: a scalar parameter further than this many standard errors from its axis' linearised optimum
#: is taken there (a simplex's 1 % tolerance is several errors of a sharp parameter; half an
#: error adds at most 1/8 to the variance). Set on the Monte Carlo of test/core/diagnosis/
#: test_experiment_standard_errors.py (at 2 the values' spread was 1.2x the standard error)
OFF_OPTIMUM_Z = 0.5
#: forward-difference step of the simulated residual's Jacobian: this share of a scale, or
#: this many radians of phase (a phase; a spatial frequency by the phase it drifts over travel)
SE_STEP = 0.02
#: a value's step bias (experiments/standard_errors.py, added to its standard error in
#: quadrature) is this many times the change of the value that the model simulated at twice its
#: substeps asks for: Richardson's factor for an error of first order in the step (2 = 1 + 1/2
#: + 1/4 + ...). The plant's error falls as m^-1 in the substeps m where its dynamics switch
#: within a substep (stick-slip, backlash contacts) and as m^-2 for smooth torques (stiffening
#: spring, ripple; frf_ident/core/simulation/plant.py), where 4/3 would do: 2 covers both.
#: Checked on two records whose bias is known, the model at 1 substep: pair seed 5804 of
#: benchmarks/diagnosis_uncertainty.py (reference plant, RK4 at 8 substeps), k2 231922 for
#: 231809, 1.30 times the change of 86.7 N m/rad at 2 substeps (second order: 4/3), so 0.65 of
#: its step bias; test/core/diagnosis/test_experiment_standard_errors.py (our plant at 16
#: substeps), Coulomb friction 11.965 for 12, 1.7 times the change of 0.0206 N m (first
#: order: 2 x 15/16), 0.85 of its step bias
STEP_BIAS_FACTOR = 2.0
#: an effect is dropped before the held-out check when each of its parameters lies within this
#: many standard errors of the nominal model's value: the record cannot tell it from the
#: nominal model
NOMINAL_Z = 2.0
