#!/usr/bin/env bash
# Regenerates the golden-test fixtures under tests/pages/data/ (small result files from tiny jobs:
# one seed, 4 episodes per job). Run only when the record format changes; then regenerate the golden
# pages with `tests/pages/run_page_test.py PAGE ACTIONSHIFT --update`.
# usage: tests/pages/make_fixtures.sh ACTIONSHIFT_BINARY [PAGE...]   (default: every page)
set -euo pipefail
cd "$(dirname "$0")/../.."
AS="$(realpath "$1")"; shift
PAGES="${*:-brittleness long_lag noise_sensitivity gate0 identifiers dualabi_pilot ladder backbone_variance delayed_oracle}"
D=tests/pages/data
S=20260718
N=4
run() { "$AS" run --seed "${SEED:-$S}" --episodes "$N" --threads 1 --progress off "$@" > /dev/null; }
for page in $PAGES; do
  rm -rf "${D:?}/$page"; mkdir -p "$D/$page"
  case $page in
  brittleness)
    # expert and a tiny Diffusion Policy (the scaled U-Net's shape, so the cost benchmark has its row; one training
    # iteration: the page's layout, not its competence), both splits, every label; dp at horizon 100 as the script runs it
    mkdir -p "$D/$page/results/clean"
    bdir=$(mktemp -d)
    "$AS" train dp --task pick_cube --demos 2 --iterations 1 --down-dims 32,64,128 --seed 1 --threads 1 \
        --out "$bdir/pick_cube.dp.asdp" > /dev/null
    for b in expert dp; do
      h=(); [ "$b" = dp ] && h=(--horizon 100)
      ACTIONSHIFT_BACKBONES_DIR="$bdir" "$AS" gate0 --backbone "$b" --task pick_cube --episodes "$N" --seed "$S" "${h[@]}" \
          --threads 1 --quiet --out "$D/$page/results/clean/$b.pick_cube.$S.json" > /dev/null || true
      for split in reference_seen reference_unseen_composition; do
        for m in no_adapt oracle grammar_belief; do
          ACTIONSHIFT_BACKBONES_DIR="$bdir" run --task pick_cube --split "$split" --method "$m" --backbone "$b" "${h[@]}" --out "$D/$page/results"
        done
        for m in exact_belief entropy_probes 'entropy_probes{calibrated}' dualabi 'dualabi{calibrated}'; do
          ACTIONSHIFT_BACKBONES_DIR="$bdir" run --task pick_cube --split "$split" --method "$m" --pool reference9 --backbone "$b" "${h[@]}" \
              --out "$D/$page/results"
        done
      done
    done
    bench="$(dirname "$AS")/../../tests/bench/actionshift_dp_bench"
    "$bench" --benchmark_filter='BM_DpControlStep/1|BM_DpChunk/1' --benchmark_repetitions=2 --benchmark_report_aggregates_only=true \
        --benchmark_format=json > "$bdir/dp_bench.json"
    "$AS" bench env --task pick_cube --threads 1 --steps 2000 --json > "$bdir/env_bench.jsonl"
    (cd "$bdir" && python3 "$OLDPWD/scripts/pages/dp_cost.py" --command "actionshift_dp_bench \
        --benchmark_filter='BM_DpControlStep/1|BM_DpChunk/1' --benchmark_repetitions=2; actionshift bench env --steps 2000" \
        dp_bench.json env_bench.jsonl pick_cube.dp.asdp) \
        > "$D/$page/results/dp_cost.json"
    rm -rf "$bdir" ;;
  delayed_oracle)
    # the expert and the DAgger MLP (the page's layout, not the Diffusion Policy's cost), every method of scripts/delayed_oracle,
    # on pick_cube; the expert on push_cube too (the page's per-task layout)
    for tb in pick_cube:expert pick_cube:mlp push_cube:expert; do
      t=${tb%%:*} b=${tb#*:}
      for m in oracle 'delayed_oracle' 'delayed_oracle{delay=1}' 'delayed_oracle{before=hold}'; do
        run --task "$t" --split reference_seen --method "$m" --backbone "$b" --out "$D/$page/results"
      done
      run --task "$t" --split reference_seen --method exact_belief --pool reference9 --backbone "$b" --out "$D/$page/results"
    done ;;
  backbone_variance)
    # three backbones of push_cube (the committed PPO and the two replicas), two seeds, every method of the pairs
    for b in ppo mlp:configs/backbones/replicas/push_cube.ppo.seed20260801.asmlp mlp:configs/backbones/replicas/push_cube.ppo.seed20260802.asmlp; do
      for seed in 20260718 20260719; do
        for m in oracle no_adapt; do N=2 SEED=$seed run --task push_cube --split reference_seen --method "$m" --backbone "$b" --out "$D/$page/results"; done
        for p in '{"probe":"none"}' '{"probe":"hold"}' '{"probe":"hold","gripper_channel":true}'; do
          N=2 SEED=$seed run --task push_cube --split reference_seen --method grammar_belief --params "$p" --backbone "$b" --out "$D/$page/results"
        done
        for m in exact_belief fixed_probes entropy_probes dualabi 'entropy_probes{calibrated}' 'dualabi{calibrated}'; do
          N=2 SEED=$seed run --task push_cube --split reference_seen --method "$m" --pool reference9 --backbone "$b" --out "$D/$page/results"
        done
      done
    done
    # and of pick_cube, with its learned identifiers (the pairs that only pick_cube has)
    for b in ppo mlp:configs/backbones/replicas/pick_cube.ppo.seed20260801.asmlp mlp:configs/backbones/replicas/pick_cube.ppo.seed20260802.asmlp; do
      for seed in 20260718 20260719; do
        for m in oracle no_adapt osi probe_osi recurrent_osi; do N=2 SEED=$seed run --task pick_cube --split reference_seen --method "$m" --backbone "$b" --out "$D/$page/results"; done
        N=2 SEED=$seed run --task pick_cube --split reference_seen --method grammar_belief --params '{"probe":"none"}' --backbone "$b" --out "$D/$page/results"
      done
    done ;;
  long_lag)
    for b in expert expert-delay-aware; do
      run --task pick_cube --split reference_long_lag --method oracle --backbone "$b" --out "$D/$page/results"
      run --task pick_cube --split reference_long_lag --method exact_belief --pool reference9 --backbone "$b" --out "$D/$page/results"
    done
    # the probing section: fixed and entropy probing on a reactive / delay-aware pair of each kind (expert: the
    # extension rows; ppo: the paper's claim with its Table 5 numbers), the `{calibrated}` variant and DualABI on the PPO pair
    for b in expert expert-delay-aware ppo ppo-delay-aware; do
      for m in fixed_probes entropy_probes; do
        run --task pick_cube --split reference_long_lag --method "$m" --pool reference9 --backbone "$b" --out "$D/$page/results"
      done
    done
    for b in ppo ppo-delay-aware; do
      for m in 'entropy_probes{calibrated}' dualabi; do
        run --task pick_cube --split reference_long_lag --method "$m" --pool reference9 --backbone "$b" --out "$D/$page/results"
      done
    done
    printf '%s\n' 'oracle@expert-delay-aware vs oracle@expert' 'exact_belief@expert-delay-aware vs exact_belief@expert' \
        'fixed_probes@ppo-delay-aware vs fixed_probes@ppo' 'entropy_probes@ppo-delay-aware vs entropy_probes@ppo' \
        'entropy_probes{calibrated}@ppo-delay-aware vs entropy_probes{calibrated}@ppo' \
        'entropy_probes vs fixed_probes' 'entropy_probes{calibrated} vs fixed_probes' > "$D/$page/pairs.txt" ;;
  noise_sensitivity)
    for mm in 0 20; do
      d="$D/$page/results/sigma_${mm}mm"; mkdir -p "$d/matched"
      sigma=$(python3 -c "print($mm / 1000)")
      "$AS" calibrate --task pick_cube --obs-noise "$sigma" --out "$d/calibration.json" > /dev/null
      for m in oracle no_adapt; do run --task pick_cube --split reference_seen --method "$m" --obs-noise "$sigma" --out "$d/matched"; done
      for m in exact_belief entropy_probes 'entropy_probes{calibrated}' dualabi 'dualabi{calibrated}'; do
        if [ "$mm" = 0 ]; then
          run --task pick_cube --split reference_seen --method "$m" --pool reference9 --out "$d/matched"
        else
          run --task pick_cube --split reference_seen --method "$m" --pool reference9 --obs-noise "$sigma" --calibration "$d/calibration.json" --out "$d/matched"
          run --task pick_cube --split reference_seen --method "$m" --pool reference9 --obs-noise "$sigma" --out "$d/noiseless_cal"
        fi
      done
    done ;;
  gate0)
    mkdir -p "$D/$page/verdicts"
    # the page the report rewrites between its markers (the text around them must survive)
    printf '%s\n' '# Gate 0 results (golden-test template)' '' 'Hand-written text above the markers is kept.' '' \
        '<!-- gate0:begin -->' '(replaced)' '<!-- gate0:end -->' '' 'Hand-written text below the markers is kept.' > "$D/$page/page.md"
    "$AS" gate0 --backbone expert --task pick_cube --episodes "$N" --threads 1 --quiet --out "$D/$page/verdicts/expert.pick_cube.json" > /dev/null || true
    "$AS" gate0 --backbone mlp --task push_cube --episodes "$N" --threads 1 --quiet --out "$D/$page/verdicts/mlp.push_cube.json" > /dev/null || true
    # a tiny Diffusion Policy as the built-in `dp`, at the horizon it is evaluated at (the page's horizon column)
    bdir=$(mktemp -d)
    "$AS" train dp --task pick_cube --demos 2 --iterations 1 --down-dims 8,16 --seed 1 --threads 1 --out "$bdir/pick_cube.dp.asdp" > /dev/null
    ACTIONSHIFT_BACKBONES_DIR="$bdir" "$AS" gate0 --backbone dp --task pick_cube --episodes "$N" --horizon 100 --threads 1 --quiet \
        --out "$D/$page/verdicts/dp.pick_cube.json" > /dev/null || true
    rm -rf "$bdir" ;;
  identifiers)
    mkdir -p "$D/$page/results/train" "$D/$page/results/eval"
    for kind in osi probe_osi recurrent_osi; do
      "$AS" train identifier --kind "$kind" --task pick_cube --seed 20260721 --episodes 1 --train-steps 20 --max-contracts 4 \
          --threads 1 --quiet --out /tmp/pages_fixture.$kind.asid --verdicts "$D/$page/results/train/$kind.s20260721.json" > /dev/null
    done
    "$AS" train identifier --kind osi --excitation random --task pick_cube --seed 20260721 --episodes 1 --train-steps 20 --max-contracts 4 \
        --threads 1 --quiet --out /tmp/pages_fixture.osi_random.asid --verdicts "$D/$page/results/train/osi_random.s20260721.json" > /dev/null
    rm -f /tmp/pages_fixture.*.asid
    for m in oracle no_adapt osi probe_osi recurrent_osi; do run --task pick_cube --split reference_seen --method "$m" --out "$D/$page/results/eval"; done ;;
  dualabi_pilot)
    for split_pool in "reference_seen reference9" "seen full"; do
      set -- $split_pool
      for m in entropy_probes 'dualabi{tau=0.4}' 'dualabi{tau=1.5}' 'dualabi{tau=10}'; do
        SEED=20260723 run --task pick_cube --split "$1" --method "$m" --pool "$2" --out "$D/$page/results"
      done
    done ;;
  ladder)
    for name in pool_reference9 pool_full grammar_passive grammar_fixed grammar_hold v2_hold_corrector control_probe_only tool_identity_hold gen_hold; do
      mkdir -p "$D/$page/results/$name"
      exp="$D/$page/results/$name/experiment.yaml"
      sed -e "s/^episodes: .*/episodes: $N/" -e "s/^seeds: .*/seeds: [$S]/" -e 's/^tasks: .*/tasks: [push_cube]/' \
          "configs/experiments/ladder/$name.yaml" > "$exp"
      # pool_reference9 also on reference_seen: the learned-backbone section's expert column (the backbone_variance
      # fixture is on push_cube / reference_seen)
      case $name in gen_*) ;; pool_reference9) sed -i -e 's/^splits: .*/splits: [reference_seen, reference_unseen_composition]/' "$exp" ;;
        *) sed -i -e 's/^splits: .*/splits: [reference_unseen_composition]/' "$exp" ;; esac
      "$AS" plan --experiment "$exp" --out "$D/$page/results/$name" > /dev/null
      "$AS" run --plan "$D/$page/results/$name/ladder_$name.plan.json" --out "$D/$page/results/$name" --threads 1 --progress off > /dev/null
      rm -f "$D/$page/results/$name/"*.plan.json "$exp"
    done ;;
  esac
  echo "$page: $(du -sk "$D/$page" | cut -f1) KB"
done
