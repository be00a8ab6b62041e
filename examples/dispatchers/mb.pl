#!/usr/bin/env perl
# MB (the paper's Eq. 7) as an external dispatcher of rpbench's round protocol (docs/protocol.md), in Perl
# with its core JSON::PP module only: score a vacant edge -pickup, a join edge saving - pickup, and keep
# nobody waiting (-10^6 m, A13).  `rpbench run --strategies mb,external
# --opt external.command="perl examples/dispatchers/mb.pl"` gives the same event log for both runs.
use strict;
use warnings;
use JSON::PP;

my $json = JSON::PP->new->canonical;
$| = 1;    # every answer line leaves at once

while (my $line = <STDIN>) {
    my $message = $json->decode($line);
    my $type = $message->{type};
    last if $type eq 'end';
    next unless $type eq 'round';
    my @scores;
    for my $edge (@{ $message->{edges} }) {
        my $kind = $edge->{kind};
        if ($kind eq 'vacant') {
            push @scores, -$edge->{pickup_m};
        } elsif ($kind eq 'join') {
            push @scores, $edge->{saving_m} - $edge->{pickup_m};
        } else {
            push @scores, -1e6;
        }
    }
    print $json->encode({ scores => \@scores }), "\n";
}
exit 0;
