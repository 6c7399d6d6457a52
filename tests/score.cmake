# Scoring against simulator truth (tracker/score.c, score_io.c, score_isbi.c, tracker/hungarian.c, cli/cmd_score.c).
elfm_add_test(test_score_hungarian test_score_hungarian.c TIMEOUT 60)
elfm_add_test(test_score test_score.c TIMEOUT 60)
elfm_add_test(test_score_depth test_score_depth.c TIMEOUT 60)
elfm_add_test(test_score_input test_score_input.c TIMEOUT 60)
elfm_add_test(test_score_frames test_score_frames.c TIMEOUT 60)
elfm_add_test(test_score_cli test_score_cli.c TIMEOUT 60)
elfm_add_test(test_score_json test_score_json.c TIMEOUT 60)
elfm_add_test(test_score_bench_cli test_score_bench_cli.c TIMEOUT 240)
