from tuflexperf.entry import main

main()
