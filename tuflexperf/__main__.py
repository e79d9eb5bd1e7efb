from tuflexperf.cli import main

main()
