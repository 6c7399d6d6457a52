# Numeric CSV tables (tracker/table.c).
elfm_add_test(test_table test_table.c)
