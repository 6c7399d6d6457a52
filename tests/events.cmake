# Event I/O (recon/ readers and writers, eventlfm info/convert).
elfm_add_test(test_events_ref test_events_ref.c TIMEOUT 120)
elfm_add_test(test_events_roundtrip test_events_roundtrip.c TIMEOUT 120)
elfm_add_test(test_events_bad test_events_bad.c TIMEOUT 120)
