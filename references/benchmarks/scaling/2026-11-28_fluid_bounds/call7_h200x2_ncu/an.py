import csv, re, sys
L = re.compile(r"(\w+)\([^()]*\)::\[lambda\(long\) \(instance (\d+)\)\]")
rows = [r for r in csv.DictReader(l for l in open(sys.argv[1]) if not l.startswith('=='))]
by = {}
for x in rows:
    m = L.search(x.get('Kernel Name', ''))
    k = m.group(1) + '#' + m.group(2) if m else x.get('Kernel Name', '')[:50]
    by.setdefault((int(x['ID']), k), {})[x['Metric Name']] = x['Metric Value']
for (i, k), d in sorted(by.items()):
    t = float(d.get('gpu__time_duration.sum', '0').replace(',', ''))
    if t > 20000:
        print(i, k, {m.split('__')[1][:28]: v for m, v in d.items()})
